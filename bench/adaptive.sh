#!/bin/sh
# bench/adaptive.sh — figures for BENCHMARKS.md "Adaptive caching" (Křivánek et al. 2006 §4,
# docs/adaptive.md).
#
#   bench/adaptive.sh [BUILD_DIR] [OUT_DIR]
#
# Part 1 (Cornell box, 128×128): records, cache-filling time, convergence overhead, and the indirect-light
# error of each strategy against a reference, over a sweep of --accuracy. The reference is the indirect AOV
# of a cache with one record per pixel centre (--accuracy 0.01 --min-radius-px 0.5, 2048 rays per record):
# every pixel's indirect light is then its own path-traced hemisphere estimate, the quantity the AOV shows,
# without interpolation. Errors are `irrcache diff` RMSE and relMSE of the .indirect.exr images.
# Part 2 (Sponza, staircase2 at reduced size; skipped with QUICK=1): adaptive passes, refinements, records,
# and the time split, next to batch.
# Prints tab-separated rows; timings are single runs (take medians yourself when comparing close numbers).
set -eu
BUILD=${1:-build-adaptive}
OUT=${2:-/tmp/irrcache-adaptive-bench}
IRR="$BUILD/irrcache"
CORNELL=scenes/cornell-box/cornell-box.json
SPP=16
mkdir -p "$OUT"

field() { python3 -c "import json,sys; d=json.load(open(sys.argv[1])); print(d.get(sys.argv[2], '') if sys.argv[2] != 'phase' else d['phases'].get(sys.argv[3], 0))" "$@"; }
diffjson() { "$IRR" diff "$1" "$2" --json | python3 -c "import json,sys; d=json.load(sys.stdin); print('%.5f\t%.5f' % (d['rmse'], d['relmse']))"; }

run() { # name strategy accuracy [extra options...]
    name=$1; strategy=$2; acc=$3; shift 3
    "$IRR" render "$CORNELL" --integrator ic --strategy "$strategy" --accuracy "$acc" --width 128 --height 128 \
        --spp $SPP --aov indirect -o "$OUT/$name.pfm" --stats "$OUT/$name.json" -q "$@"
    s="$OUT/$name.json"
    printf '%s\t%s\t%s\t%s\t%s\t%s\t%.3f\t%.3f\t%.3f\t%s\n' "$strategy" "$acc" "$*" "$(field "$s" records)" \
        "$(field "$s" passes)" "$(field "$s" refinements)" "$(field "$s" phase gathering)" \
        "$(field "$s" phase insertion)" "$(field "$s" phase convergence)" \
        "$(diffjson "$OUT/$name.indirect.exr" "$OUT/ref.indirect.exr")"
}

if [ ! -f "$OUT/ref.indirect.exr" ]; then
    "$IRR" render "$CORNELL" --integrator ic --strategy lazy --accuracy 0.01 --min-radius-px 0.5 --rays 2048 \
        --width 128 --height 128 --spp $SPP --aov indirect -o "$OUT/ref.pfm" --stats "$OUT/ref.json" -q
fi
echo "# reference: $(field "$OUT/ref.json" records) records (one per pixel centre)"
printf 'strategy\ta\textra\trecords\tpasses\trefinements\tgather_s\tinsert_s\tconvergence_s\trmse\trelmse\n'
for a in 0.1 0.15 0.25 0.4 0.6 1.0 1.5; do
    run "lazy-$a" lazy "$a"
    run "batch-$a" batch "$a"
done
for a in 0.25 0.4 0.6 1.0; do
    run "adaptive-$a" adaptive "$a"
    run "adaptive-$a-w01" adaptive "$a" --weber 0.01
done

[ "${QUICK:-0}" = 1 ] && exit 0
printf '\nscene\tstrategy\trecords\tpasses\trefinements\tseconds\tgather_s\tinsert_s\tconvergence_s\n'
for scene in sponza staircase2; do
    for strategy in adaptive batch; do
        "$IRR" render "scenes/$scene.json" --integrator ic --strategy "$strategy" --width 192 --height 128 \
            --spp 1 -o "$OUT/$scene-$strategy.png" --stats "$OUT/$scene-$strategy.json" -q
        s="$OUT/$scene-$strategy.json"
        printf '%s\t%s\t%s\t%s\t%s\t%.2f\t%.2f\t%.2f\t%.3f\n' "$scene" "$strategy" "$(field "$s" records)" \
            "$(field "$s" passes)" "$(field "$s" refinements)" "$(field "$s" seconds)" \
            "$(field "$s" phase gathering)" "$(field "$s" phase insertion)" \
            "$(field "$s" phase convergence)"
    done
done
