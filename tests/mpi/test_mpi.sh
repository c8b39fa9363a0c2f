#!/usr/bin/env bash
# test_mpi.sh IRRCACHE HAS_MPI — `mpirun -np N irrcache render` gives the bytes a single process gives:
#   1. the Cornell box with the cache (batch; its image, cache file, record counts per pass, the job's rays)
#      and with the path tracer, at 1, 2, 3 and 5 ranks of 1 or 2 threads each, against the same build run
#      without mpirun (one process); the adaptive strategy (image, counts and rays), a loaded cache and
#      radiance caching at 3 ranks, a 12x300 image (bands of shading points and look-ups that leave rows
#      out) at 3 and 5; an image and its AOVs (films in a row) at 3, 7 and 9 ranks, more than its tiles; an
#      image smaller than a tile at 3; `irrcache points` (cache and path tracer) at 2, 3 and 5 ranks;
#      the path tracer at 3 ranks through the chunked all-gather of exchanges over 2 GiB (threshold lowered);
#   2. lazy construction under 2 ranks is refused with a message naming the strategy;
#   3. one rank whose scene does not load (mpirun's MPMD form: two ranks get the scene, the third a
#      missing file) stops the job: non-zero exit within seconds, the message names the rank and the
#      file, and no output is written;
#   4. a rank killed during the final render ends the job within seconds, leaving no output or temporary file.
# Images are compared as PFM (the pixels alone: an EXR's header says how long the render took).
# Skips (77) when the build has no MPI. Runs as root in CI through Open MPI's own switches (set here,
# never in the program).
set -euo pipefail
bin=${1:?usage: test_mpi.sh IRRCACHE HAS_MPI}
if [ "${2:-}" != 1 ] && [ "${2:-}" != ON ] && [ "${2:-}" != TRUE ]; then
  echo "skipped: this build has no MPI (configure with MPI installed: scripts/deps.sh)"
  exit 77
fi
command -v mpirun >/dev/null || { echo "skipped: mpirun not found (scripts/deps.sh installs openmpi-bin)"; exit 77; }
export OMPI_ALLOW_RUN_AS_ROOT=1 OMPI_ALLOW_RUN_AS_ROOT_CONFIRM=1
src=$(cd "$(dirname "$0")/../.." && pwd)
scene=$src/scenes/cornell-box/cornell-box.json
tmp=$(mktemp -d "${TMPDIR:-/tmp}/irrcache-mpi.XXXXXX")
trap 'rm -rf "$tmp"' EXIT
cd "$tmp"
common=(--width 40 --height 40 --quiet)
ic=(--integrator ic --spp 8 --rays 256)
pt=(--integrator pt --spp 4)
fail=0

# The counts that must not depend on the ranks: records, passes, records per pass, the job's rays.
counts() { python3 -c 'import json,sys; d=json.load(open(sys.argv[1])); print(d.get("records"), d.get("passes"), d.get("records_per_pass"), d["spp"], d.get("spp_max"), d["rays"], d.get("gather_rays"))' "$1"; }
same() { # same WHAT FILE REFERENCE
  if cmp -s "$2" "$3"; then return 0; fi
  echo "FAIL: $1: $2 differs from $3"; fail=1
}

"$bin" render "$scene" "${common[@]}" "${ic[@]}" --threads 2 -o ic.pfm --stats ic.json --save-cache ic.cache
"$bin" render "$scene" "${common[@]}" "${pt[@]}" --threads 2 -o pt.pfm
"$bin" render "$scene" "${common[@]}" "${ic[@]}" --strategy adaptive --threads 2 -o ad.pfm --stats ad.json
"$bin" render "$scene" "${common[@]}" "${ic[@]}" --threads 2 --load-cache ic.cache -o load.pfm
for np in 1 2 3 5; do
  for t in 1 2; do
    tag=ic-$np-$t
    mpirun --oversubscribe -np $np "$bin" render "$scene" "${common[@]}" "${ic[@]}" --threads $t -o $tag.pfm \
      --stats $tag.json --save-cache $tag.cache
    same "batch image, $np ranks x $t threads" $tag.pfm ic.pfm
    same "cache file, $np ranks x $t threads" $tag.cache ic.cache
    if [ "$(counts $tag.json)" != "$(counts ic.json)" ]; then
      echo "FAIL: record counts at $np ranks x $t threads: $(counts $tag.json), one process: $(counts ic.json)"
      fail=1
    fi
    if [ $np -gt 1 ]; then
      python3 - "$tag.json" "$np" <<'PY' || fail=1
import json, sys
d = json.load(open(sys.argv[1])); n = int(sys.argv[2])
assert d["ranks"] == n and len(d["per_rank"]) == n, "stats: ranks"
assert sum(r["records_gathered"] for r in d["per_rank"]) == d["records"], "stats: records gathered add up"
assert sum(r["pixel_samples"] for r in d["per_rank"]) == d["spp"] * d["width"] * d["height"], "stats: samples add up"
assert all(r["comm_seconds"] >= 0 and r["comm_bytes"] > 0 for r in d["per_rank"]), "stats: communication"
PY
    fi
  done
  mpirun --oversubscribe -np $np "$bin" render "$scene" "${common[@]}" "${pt[@]}" --threads $((np % 2 + 1)) -o pt-$np.pfm
  same "path-traced image, $np ranks" pt-$np.pfm pt.pfm
done
# An all-gather too large for MPI's int counts (above 2 GiB: a huge image's pixels) goes rank by rank in
# chunks; the test lowers the threshold to 1000 bytes so that the path tracer's image (19 kB) takes it.
IRRCACHE_MPI_ALLGATHER_LIMIT=1000 mpirun --oversubscribe -x IRRCACHE_MPI_ALLGATHER_LIMIT -np 3 "$bin" render "$scene" \
  "${common[@]}" "${pt[@]}" --threads 1 -o pt-large.pfm
same "path-traced image through the large all-gather, 3 ranks" pt-large.pfm pt.pfm
mpirun --oversubscribe -np 3 "$bin" render "$scene" "${common[@]}" "${ic[@]}" --strategy adaptive --threads 1 -o ad-3.pfm \
  --stats ad-3.json
same "adaptive image, 3 ranks" ad-3.pfm ad.pfm
if [ "$(counts ad-3.json)" != "$(counts ad.json)" ]; then
  echo "FAIL: adaptive counts at 3 ranks: $(counts ad-3.json), one process: $(counts ad.json)"
  fail=1
fi
mpirun --oversubscribe -np 3 "$bin" render "$scene" "${common[@]}" "${ic[@]}" --threads 1 --load-cache ic.cache -o load-3.pfm
same "image from a loaded cache, 3 ranks" load-3.pfm load.pfm
# The hit stage (records where hemisphere rays land) gathers its records shared among the ranks too.
"$bin" render "$scene" "${common[@]}" "${ic[@]}" --hit-records on --threads 2 -o hit.pfm
mpirun --oversubscribe -np 3 "$bin" render "$scene" "${common[@]}" "${ic[@]}" --hit-records on --threads 1 -o hit-3.pfm
same "batch image with hit records, 3 ranks" hit-3.pfm hit.pfm

# A tall image: each rank computes the shading points of its rows and a 64-row band around them, and the
# look-ups' luminances travel only that far (an all-to-all), so here every rank's band leaves rows out.
"$bin" render "$scene" --width 12 --height 300 --quiet "${ic[@]}" --threads 2 -o tall.pfm --save-cache tall.cache
for np in 3 5; do
  mpirun --oversubscribe -np $np "$bin" render "$scene" --width 12 --height 300 --quiet "${ic[@]}" --threads 1 \
    -o tall-$np.pfm --save-cache tall-$np.cache
  same "12x300 image, $np ranks" tall-$np.pfm tall.pfm
  same "12x300 cache file, $np ranks" tall-$np.cache tall.cache
done

# Films in a row, each streaming its finished tiles: the image, then its indirect and glossy AOVs (no
# collective between them). A 33x17 image has 6 tiles, the last column a pixel wide, so 7 and 9 ranks
# leave ranks without a tile; a 7x5 image is smaller than one tile. The AOVs' EXR headers say how long the
# render took: compared without that field.
exr_same() { # exr_same WHAT FILE REFERENCE
  python3 - "$2" "$3" <<'PY' && return 0
import re, sys
def body(p):
    return re.sub(rb'(irrcache:seconds\x00string\x00....)[0-9.]+', rb'\1', open(p, 'rb').read(), flags=re.S)
sys.exit(body(sys.argv[1]) != body(sys.argv[2]))
PY
  echo "FAIL: $1: $2 differs from $3"; fail=1
}
"$bin" render "$scene" --width 33 --height 17 --quiet "${ic[@]}" --threads 1 --aov indirect,glossy -o row.pfm
"$bin" render "$scene" --width 7 --height 5 --quiet "${pt[@]}" --threads 1 -o tiny.pfm
for np in 3 7 9; do
  mpirun --oversubscribe -np $np "$bin" render "$scene" --width 33 --height 17 --quiet "${ic[@]}" --threads 1 \
    --aov indirect,glossy -o row-$np.pfm
  same "33x17 image before its AOVs, $np ranks" row-$np.pfm row.pfm
  exr_same "33x17 indirect AOV, $np ranks" row-$np.indirect.exr row.indirect.exr
  exr_same "33x17 glossy AOV, $np ranks" row-$np.glossy.exr row.glossy.exr
done
mpirun --oversubscribe -np 3 "$bin" render "$scene" --width 7 --height 5 --quiet "${pt[@]}" --threads 2 -o tiny-3.pfm
same "7x5 image (one tile), 3 ranks" tiny-3.pfm tiny.pfm

# Radiance caching on the glossy floor: its records are split among the ranks like irradiance records.
glossy=$src/scenes/cornell-box-glossy/cornell-box-glossy-20.json
"$bin" render "$glossy" "${common[@]}" "${ic[@]}" --radiance-cache on --threads 2 -o glossy.pfm --save-cache glossy.cache
mpirun --oversubscribe -np 3 "$bin" render "$glossy" "${common[@]}" "${ic[@]}" --radiance-cache on --threads 1 \
  -o glossy-3.pfm --save-cache glossy-3.cache
same "radiance cache image, 3 ranks" glossy-3.pfm glossy.pfm
same "radiance cache file, 3 ranks" glossy-3.cache glossy.cache

# Sensor points: the points read by rank 0 (here from standard input) and broadcast; records and points
# shared among the ranks.
python3 -c 'import random; random.seed(3)
for i in range(48): print(random.uniform(-0.9, 0.9), random.uniform(0.05, 1.5), random.uniform(-0.9, 0.9), 0, 1, 0)' >pts.txt
"$bin" points "$scene" --points pts.txt --threads 2 --rays 256 --light-samples 32 -o points.txt
"$bin" points "$scene" --points pts.txt --integrator pt --samples 32 --threads 2 -o points-pt.txt
for np in 2 3 5; do
  mpirun --oversubscribe -np $np "$bin" points "$scene" --points - --threads 1 --rays 256 --light-samples 32 \
    -o points-$np.txt <pts.txt
  same "sensor points (cache), $np ranks" points-$np.txt points.txt
  mpirun --oversubscribe -np $np "$bin" points "$scene" --points pts.txt --integrator pt --samples 32 --threads 1 \
    -o points-pt-$np.txt
  same "sensor points (path tracer), $np ranks" points-pt-$np.txt points-pt.txt
done

# Lazy construction is serial: refused under several ranks, with the reason.
if mpirun --oversubscribe -np 2 "$bin" render "$scene" "${common[@]}" "${ic[@]}" --strategy lazy -o lazy.pfm \
     2>lazy.err; then
  echo "FAIL: lazy under 2 ranks was not refused"; fail=1
elif ! grep -q "lazy" lazy.err || [ -e lazy.pfm ]; then
  echo "FAIL: lazy under 2 ranks: no message naming the strategy, or an image was written:"; cat lazy.err; fail=1
fi

# A rank that cannot load its scene stops the whole job, at once, with one message and no output.
start=$(date +%s)
if timeout 60 mpirun --oversubscribe -np 2 "$bin" render "$scene" "${common[@]}" "${ic[@]}" -o bad.pfm : \
     -np 1 "$bin" render "$tmp/missing.json" "${common[@]}" "${ic[@]}" -o bad.pfm 2>bad.err; then
  echo "FAIL: a rank without its scene: the job exited 0"; fail=1
fi
took=$(( $(date +%s) - start ))
if [ $took -gt 20 ]; then echo "FAIL: a rank without its scene: the job took ${took}s to stop"; fail=1; fi
if ! grep -q "rank 2 of 3.*missing.json" bad.err; then
  echo "FAIL: a rank without its scene: no message naming rank 2 and the file:"; cat bad.err; fail=1
fi
if [ "$(grep -c "irrcache render" bad.err)" != 1 ]; then
  echo "FAIL: a rank without its scene: not exactly one message:"; cat bad.err; fail=1
fi
if ls bad.pfm* >/dev/null 2>&1; then echo "FAIL: a rank without its scene: an output was written"; fail=1; fi

# A rank that dies in the middle of the render (killed by a signal) ends the job: non-zero exit within
# seconds, and neither an output nor a temporary file is left behind.
mpirun --oversubscribe -np 2 "$bin" render "$scene" --width 96 --height 96 --quiet --integrator ic --spp 4096 \
  --threads 1 -o killed.pfm 2>killed.err &
job=$!
victim=
for _ in $(seq 1 100); do # mpirun starts the ranks as its children: the last of the two
  [ "$(pgrep -c -P $job)" -ge 2 ] && victim=$(pgrep -n -P $job) && break
  sleep 0.1
done
sleep 2
start=$(date +%s)
if [ -n "$victim" ]; then kill -KILL "$victim"; fi
if wait $job; then echo "FAIL: a rank killed during the render: the job exited 0"; fail=1; fi
took=$(( $(date +%s) - start ))
if [ -z "$victim" ]; then echo "FAIL: a rank killed during the render: no rank process found"; fail=1; fi
if [ $took -gt 20 ]; then echo "FAIL: a rank killed during the render: the job took ${took}s to stop"; fail=1; fi
if ls killed.pfm* >/dev/null 2>&1; then
  echo "FAIL: a rank killed during the render: an output or temporary file was left:"; ls -a; fail=1
fi

[ $fail = 0 ] && echo "mpi: every rank count gave the single process's bytes"
exit $fail
