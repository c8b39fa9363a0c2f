#!/usr/bin/env bash
# test_allgather.sh TEST_ALLGATHER — the command's all-gather (test_allgather.c) at 2 to 9 ranks: powers of
# two and not, Bruck's last round short or whole. Runs as root in CI through Open MPI's own switches.
set -euo pipefail
bin=${1:?usage: test_allgather.sh TEST_ALLGATHER}
command -v mpirun >/dev/null || { echo "skipped: mpirun not found (scripts/deps.sh installs openmpi-bin)"; exit 77; }
export OMPI_ALLOW_RUN_AS_ROOT=1 OMPI_ALLOW_RUN_AS_ROOT_CONFIRM=1
fail=0
for np in 2 3 4 5 6 7 8 9; do
  timeout 120 mpirun --oversubscribe -np $np "$bin" || fail=1
done
exit $fail
