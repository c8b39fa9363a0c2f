#!/usr/bin/env bash
# Golden outputs of a fixed set of small Cornell-box renders, for changes that must not change any
# image: every output file's SHA-256 (stats JSON with times and rates removed, phase names kept; the
# render time and the version in EXR headers blanked).
#
#   bash tests/golden/golden.sh IRRCACHE_BINARY            print the hashes
#   bash tests/golden/golden.sh IRRCACHE_BINARY --check    compare with tests/golden/hashes.txt
#   bash tests/golden/golden.sh IRRCACHE_BINARY --record   rewrite tests/golden/hashes.txt
#
# The hashes are those of one machine and compiler (floating point is not the same everywhere), so
# this is a tool for a refactor, run before and after, and not part of the test suite. The scenes are
# named by a path relative to the work folder (a link to the checkout's scenes), so that the stats and
# EXR headers, which record the scene's path, are the same wherever the checkout lies.
set -euo pipefail
bin=$(realpath "$1"); mode=${2:-print}
root=$(cd "$(dirname "$0")/../.." && pwd)
work=$(mktemp -d); trap 'rm -rf "$work"' EXIT
cd "$work"
ln -s "$root/scenes" scenes
scene=scenes/cornell-box/cornell-box.json
r() { # name, args...
  local name=$1; shift
  "$bin" render "$scene" --width 48 --height 48 --threads 2 --quiet -o "$name.exr" --stats "$name.json" "$@"
}
r pt --spp 8
r pt_random --spp 8 --sampler random --adaptive-sampling on
r batch --integrator ic --spp 8 --aov indirect,records,density,amap --records-json batch.records.json
r batch_tl --integrator ic --spp 4 --weight tl --no-gradients --gather progressive
r lazy --integrator ic --spp 4 --strategy lazy --rays 128
r recursive --integrator ic --spp 4 --strategy lazy --recursive --bounces 2 --rays 128
r adaptive --integrator ic --spp 4 --strategy adaptive --rays 128 --aov amap
r nograd --integrator ic --spp 4 --no-gradients --no-neighbor-clamp --no-validity-clamp --path-traced-gather
r save --integrator ic --spp 4 --rays 256 --save-cache c.irc
r load --integrator ic --spp 4 --rays 256 --load-cache c.irc --seed 7
r emitters --integrator ic --spp 4 --rays 256 --large-emitters off --max-depth 3
# Large emitters the records carry (staircase2's windows; its meshes are in ../shared/scenes).
"$bin" render scenes/staircase2.json --width 64 --height 36 --spp 4 --integrator ic --rays 128 --threads 2 \
  --quiet -o staircase.exr --stats staircase.json
for f in *.json; do
  python3 - "$f" <<'PY'
import json, sys
p = sys.argv[1]
d = json.load(open(p))
if isinstance(d, dict):
    for k in ("seconds", "rays_per_second", "settings"):
        d.pop(k, None)
    d["phases"] = list(d.get("phases", {}))  # the names and their order, not the times
    json.dump(d, open(p, "w"), sort_keys=True)
PY
done
# EXR headers carry the render's time (irrcache:seconds, fixed width) and the library's version: blank
# both, so that neither a slow run nor a version bump of the same length changes a hash.
for f in *.exr; do
  python3 - "$f" <<'PY'
import struct, sys
p = sys.argv[1]
b = bytearray(open(p, "rb").read())
for name, fill in ((b"seconds", b"0"), (b"version", b"x")):
    key = b"irrcache:" + name + b"\0string\0"
    i = b.find(key)
    if i >= 0:
        j = i + len(key)
        n = struct.unpack_from("<i", b, j)[0]
        b[j + 4:j + 4 + n] = fill * n
open(p, "wb").write(b)
PY
done
sha256sum $(find . -maxdepth 1 -type f -printf "%f\n" | LC_ALL=C sort) > "$work/hashes.txt.new"
mv "$work/hashes.txt.new" "$work/HASHES"
case $mode in
  print) cat HASHES ;;
  --record) cp HASHES "$root/tests/golden/hashes.txt"; echo "recorded $(wc -l < HASHES) hashes" ;;
  --check)
    if diff -u "$root/tests/golden/hashes.txt" HASHES; then echo "golden: all $(wc -l < HASHES) outputs identical"
    else echo "golden: outputs differ"; exit 1; fi ;;
  *) echo "unknown mode $mode"; exit 2 ;;
esac
