#!/usr/bin/env bash
# Instructions per path-tracer sample of one or more builds on the same scenes, counted by callgrind (the
# inclusive cost of the film's tile loop, one thread): a measure of per-sample cost that a shared machine's
# load does not move, for comparing builds whose images are identical (checked: the script says when not).
#
#   bash bench/pt_instructions.sh BUILD_DIR [BUILD_DIR ...] -- SCENE [SCENE ...]
#
# Renders 64×64 at 8 spp (seed 1). Prints "build scene instructions-per-sample" lines; ratios between builds
# are what to record (BENCHMARKS.md). Needs valgrind; slow (about a minute per render).
set -euo pipefail
builds=()
while [ $# -gt 0 ] && [ "$1" != -- ]; do builds+=("$(realpath "$1")"); shift; done
shift
work=$(mktemp -d); trap 'rm -rf "$work"' EXIT
for scene in "$@"; do
  first=
  for b in "${builds[@]}"; do
    out=$work/cg.out
    valgrind --tool=callgrind --callgrind-out-file="$out" "$b/irrcache" render "$scene" --width 64 --height 64 \
      --spp 8 --threads 1 --seed 1 -q -o "$work/img.pfm" >/dev/null 2>&1
    n=$(callgrind_annotate --inclusive=yes "$out" | awk '/render_tile/ {gsub(",", "", $1); print $1; exit}')
    echo "$b $(basename "$scene" .json) $(python3 -c "print(round($n / (64 * 64 * 8), 1))")"
    if [ -z "$first" ]; then cp "$work/img.pfm" "$work/first.pfm"; first=1
    elif ! cmp -s "$work/img.pfm" "$work/first.pfm"; then echo "  (its image differs from the first build's)"; fi
  done
done
