#!/bin/sh
# bench/mpi_netns.sh — the communication model of bench/mpi_model.py against a real, slow link: two ranks
# in two network namespaces joined by a veth pair whose both ends are limited by a token bucket (tc tbf),
# Open MPI over TCP between them (its launcher reaches the second namespace through a small rsh agent).
# For each rate (and once unlimited) a render of SCENE with --stats; prints per rank the seconds spent
# communicating, the bytes received and bytes × 8 / rate, the time the model charges for moving them.
# Every image must be bit-identical to the unlimited run's. Needs root (ip netns, tc); Linux's netem is not
# required (latency is not emulated, only the rate).
#
#   sudo sh bench/mpi_netns.sh [BUILD_DIR] [WIDTH HEIGHT] [RATES_MBIT...]
set -eu
BUILD=${1:-build}
W=${2:-160}
H=${3:-90}
shift 3 2>/dev/null || shift $#
RATES=${*:-100 10}
SCENE=${SCENE:-scenes/sponza.json}
IRR=$(realpath "$BUILD/irrcache")
OUT=$(mktemp -d /tmp/mpi_netns.XXXXXX)
export OMPI_ALLOW_RUN_AS_ROOT=1 OMPI_ALLOW_RUN_AS_ROOT_CONFIRM=1
cleanup() { ip netns del icb0 2>/dev/null || true; ip netns del icb1 2>/dev/null || true; }
trap cleanup EXIT
cleanup
ip netns add icb0
ip netns add icb1
ip link add icbv0 type veth peer name icbv1
for n in 0 1; do
    ip link set icbv$n netns icb$n
    ip netns exec icb$n ip addr add 10.77.0.$((n + 1))/24 dev icbv$n
    ip netns exec icb$n ip link set lo up
    ip netns exec icb$n ip link set icbv$n up
done
cat >"$OUT/rsh" <<'EOF'
#!/bin/sh
host=$1; shift
case $host in 10.77.0.1) ns=icb0 ;; 10.77.0.2) ns=icb1 ;; *) echo "rsh: unknown host $host" >&2; exit 1 ;; esac
exec ip netns exec $ns sh -c "$*"
EOF
chmod +x "$OUT/rsh"
run() { # name
    ip netns exec icb0 mpirun --oversubscribe -np 2 --host 10.77.0.1:1,10.77.0.2:1 --mca plm_rsh_agent "$OUT/rsh" \
        --mca btl tcp,self --mca btl_tcp_if_include 10.77.0.0/24 --mca oob_tcp_if_include 10.77.0.0/24 \
        "$IRR" render "$(realpath "$SCENE")" --integrator ic --width "$W" --height "$H" -q --threads 1 \
        -o "$OUT/$1.pfm" --stats "$OUT/$1.json" 2>/dev/null
}
run free
for r in $RATES; do
    for n in 0 1; do ip netns exec icb$n tc qdisc replace dev icbv$n root tbf rate "${r}mbit" burst 64kbit latency 400ms; done
    run "rate$r"
    cmp "$OUT/rate$r.pfm" "$OUT/free.pfm" || { echo "bench/mpi_netns.sh: the image at $r Mbit/s differs" >&2; exit 1; }
done
python3 - "$OUT" $RATES <<'EOF'
import json, sys
out, rates = sys.argv[1], sys.argv[2:]
free = json.load(open(out + "/free.json"))["per_rank"]
print("| link | rank | seconds communicating | more than unlimited | bytes received | bytes × 8 / rate |")
print("|---|---|---|---|---|---|")
for r in [None] + rates:
    d = json.load(open(out + ("/free.json" if r is None else "/rate%s.json" % r)))["per_rank"]
    for k, p in enumerate(d):
        model = "—" if r is None else "%.3f s" % (p["comm_bytes"] * 8 / (float(r) * 1e6))
        extra = "—" if r is None else "%.3f s" % (p["comm_seconds"] - free[k]["comm_seconds"])
        print("| %s | %d | %.3f s | %s | %d | %s |" % ("unlimited" if r is None else r + " Mbit/s", k,
                                                   p["comm_seconds"], extra, p["comm_bytes"], model))
EOF
echo "bench/mpi_netns.sh: runs in $OUT"
