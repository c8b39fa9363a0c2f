#!/usr/bin/env bash
# Compares two builds on the same work, alternated (old, new, old, new, …) so that the machine's drift
# falls on both: bench_trace (rays and path-tracer samples per second), bench_lookup --load (look-ups
# per second on the same saved caches) and the render phases of a path-traced and a cache render.
#
#   bash bench/compare_builds.sh OLD_BUILD_DIR NEW_BUILD_DIR [ROUNDS]
#
# Prints one line per measurement and build; the ratios new/old are what to record (BENCHMARKS.md).
set -euo pipefail
old=$1 new=$2 rounds=${3:-3}
root=$(cd "$(dirname "$0")/.." && pwd)
scene=$root/scenes/cornell-box/cornell-box.json
work=$(mktemp -d); trap 'rm -rf "$work"' EXIT
mkdir -p "$work/lk"
# Saved by the old build: a newer build reads every older cache file version.
"$old/bench/bench_lookup" --save "$work/lk" "$scene" 320 180 >/dev/null
phase() { python3 -c "import json,sys; print(json.load(open(sys.argv[1]))['phases'][sys.argv[2]])" "$@"; }
for r in $(seq "$rounds"); do
  for b in old new; do
    dir=$old; [ $b = new ] && dir=$new
    "$dir/bench/bench_trace" "$scene" 320 180 3 | awk -v b=$b '/^camera|^hemisphere/ {print b, $1 "_module1_Mrays", $4} /path tracer, 1 thread/ {print b, "pt_1thread_Msamples", $5}'
    "$dir/bench/bench_lookup" --load "$work/lk" | awk -v b=$b '/frozen\+hint  |frozen batch/ {print b, "lookup_clamp_" $3 "_" ($5 == "batch" ? "batch" : "hint"), ($5 == "batch" ? $11 : $10)}'
    "$dir/irrcache" render "$scene" --width 256 --height 256 --spp 16 -q -o "$work/pt.exr" --stats "$work/pt.json"
    echo "$b pt_render_s $(phase "$work/pt.json" render)"
    "$dir/irrcache" render "$scene" --integrator ic --width 256 --height 256 --spp 64 -q -o "$work/ic.exr" \
      --stats "$work/ic.json"
    echo "$b ic_final_render_s $(phase "$work/ic.json" 'final render')"
    echo "$b ic_gathering_s $(phase "$work/ic.json" gathering)"
  done
done > "$work/all.txt"
cat "$work/all.txt"
# Medians per build and the ratio new/old (above 1: new is faster, for rates; slower, for seconds).
python3 - "$work/all.txt" <<'PY'
import collections, statistics, sys
v = collections.defaultdict(list)
for line in open(sys.argv[1]):
    b, k, x = line.split()
    v[(b, k)].append(float(x))
for k in sorted({k for _, k in v}):
    o, n = statistics.median(v[("old", k)]), statistics.median(v[("new", k)])
    print(f"{k:32s} old {o:10.4g}  new {n:10.4g}  new/old {n / o:6.3f}")
PY
