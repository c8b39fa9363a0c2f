#!/usr/bin/env bash
# Set-up command 1: install missing packages, build, render the bundled Cornell box to
# out/cornell.exr and out/cornell.png with the irradiance cache (the summary line says how long it
# took and how many records it made). Safe to re-run; extra arguments go to irrcache render.
set -euo pipefail
cd "$(dirname "$0")/.."
bash scripts/deps.sh
cmake -S . -B build -DCMAKE_BUILD_TYPE=Release >/dev/null
cmake --build build -j"$(nproc)"
mkdir -p out
./build/irrcache render scenes/cornell-box/cornell-box.json --integrator ic -o out/cornell.exr -o out/cornell.png "$@"
echo "wrote out/cornell.exr and out/cornell.png"
