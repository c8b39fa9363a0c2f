#!/usr/bin/env bash
# Set-up command 1: install missing packages, build, render the bundled Cornell box to
# out/cornell.exr and out/cornell.png. Safe to re-run.
set -euo pipefail
cd "$(dirname "$0")/.."
bash scripts/deps.sh
cmake -S . -B build -DCMAKE_BUILD_TYPE=Release >/dev/null
cmake --build build -j"$(nproc)"
mkdir -p out
./build/irrcache render scenes/cornell-box/cornell-box.json -o out/cornell.exr -o out/cornell.png "$@"
echo "wrote out/cornell.exr and out/cornell.png"
