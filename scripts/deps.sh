#!/usr/bin/env bash
# Installs the Debian 12 packages irrcache needs, only those missing (safe to re-run).
set -euo pipefail
pkgs=(build-essential cmake pkg-config libembree-dev libassimp-dev libcjson-dev libopenexr-dev libstb-dev zlib1g-dev python3)
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
