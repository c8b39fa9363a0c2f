#!/bin/sh
# bench/mpi.sh — figures for BENCHMARKS.md "Several processes (MPI)": one scene rendered by 1 rank × 2
# threads (no mpirun), by 2 ranks × 1 thread (mpirun) and by 1 rank × 1 thread, the first two alternated
# ROUNDS times, each run's --stats kept; then bench/mpi_model.py reads them.
#
#   bench/mpi.sh [BUILD_DIR] [OUT_DIR] [WIDTH HEIGHT] [ROUNDS]
#
# Every image must be bit-identical to the first (checked with cmp; the script stops otherwise).
set -eu
BUILD=${1:-build}
OUT=${2:-/tmp/irrcache-mpi-bench}
W=${3:-320}
H=${4:-180}
ROUNDS=${5:-2}
SCENE=${SCENE:-scenes/sponza.json}
IRR="$BUILD/irrcache"
export OMPI_ALLOW_RUN_AS_ROOT=1 OMPI_ALLOW_RUN_AS_ROOT_CONFIRM=1  # a CI container runs as root
mkdir -p "$OUT"
common="--integrator ic --width $W --height $H -q"
check() { cmp "$OUT/$1.pfm" "$OUT/1x2-1.pfm" || { echo "bench/mpi.sh: $1.pfm differs from 1x2-1.pfm" >&2; exit 1; }; }
i=1
while [ $i -le "$ROUNDS" ]; do
    "$IRR" render "$SCENE" $common --threads 2 -o "$OUT/1x2-$i.pfm" --stats "$OUT/1x2-$i.json"
    check 1x2-$i
    mpirun -np 2 --bind-to core "$IRR" render "$SCENE" $common --threads 1 -o "$OUT/2x1-$i.pfm" --stats "$OUT/2x1-$i.json"
    check 2x1-$i
    i=$((i + 1))
done
"$IRR" render "$SCENE" $common --threads 1 -o "$OUT/1x1.pfm" --stats "$OUT/1x1.json"
check 1x1
echo "bench/mpi.sh: runs in $OUT; next: python3 bench/mpi_model.py $OUT"
