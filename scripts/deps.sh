#!/usr/bin/env bash
# Installs the Debian 12 packages irrcache needs, only those missing (safe to re-run).
set -euo pipefail
# libopenmpi-dev and openmpi-bin: the MPI build of the command (mpirun -np N irrcache render …).
# clang and libclang-rt-dev (libFuzzer and the sanitizer runtimes): the fuzz stage of scripts/test.sh.
pkgs=(build-essential cmake pkg-config libembree-dev libassimp-dev libcjson-dev libopenexr-dev libjpeg-dev libstb-dev zlib1g-dev libxml2-dev python3
      libopenmpi-dev openmpi-bin
      clang libclang-rt-dev)
missing=()
for p in "${pkgs[@]}"; do
  dpkg-query -W -f='${Status}' "$p" 2>/dev/null | grep -q "install ok installed" || missing+=("$p")
done
if [ ${#missing[@]} -gt 0 ]; then
  echo "irrcache: installing ${missing[*]}" >&2
  SUDO=""
  if [ "$(id -u)" -ne 0 ]; then SUDO="sudo"; fi
  $SUDO apt-get update -qq
  DEBIAN_FRONTEND=noninteractive $SUDO apt-get install -y -qq "${missing[@]}"
fi
