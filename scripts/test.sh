#!/usr/bin/env bash
# Set-up command 2: install missing packages, build with warnings as errors, run the whole test
# suite, then again under AddressSanitizer + UndefinedBehaviorSanitizer. Safe to re-run.
# Ends with one line "N passed, N failed" (tests over both builds).
set -uo pipefail
cd "$(dirname "$0")/.."
bash scripts/deps.sh || exit 1
jobs=$(nproc)
total_pass=0; total_fail=0
run_suite() { # name, build dir, cmake args...
  local name=$1 dir=$2; shift 2
  echo "== $name build ($dir)"
  if ! cmake -S . -B "$dir" -DIC_WERROR=ON "$@" >/dev/null || ! cmake --build "$dir" -j"$jobs"; then
    echo "$name: build failed"; total_fail=$((total_fail + 1)); return
  fi
  local log; log=$(mktemp)
  ctest --test-dir "$dir" --output-on-failure -j"$jobs" 2>&1 | tee "$log"
  local n_total n_fail
  n_total=$(sed -n 's/.*tests failed out of \([0-9]*\).*/\1/p' "$log" | tail -n1)
  n_fail=$(sed -n 's/.*, \([0-9]*\) tests failed out of.*/\1/p' "$log" | tail -n1)
  if [ -z "$n_total" ]; then n_total=1; n_fail=1; fi
  total_pass=$((total_pass + n_total - n_fail)); total_fail=$((total_fail + n_fail))
  rm -f "$log"
}
run_suite release build -DCMAKE_BUILD_TYPE=Release
run_suite sanitize build-asan -DCMAKE_BUILD_TYPE=RelWithDebInfo -DIC_SANITIZE=ON -DIC_BUILD_BENCH=OFF
echo "$total_pass passed, $total_fail failed"
[ "$total_fail" -eq 0 ]
