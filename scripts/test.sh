#!/usr/bin/env bash
# Set-up command 2: install missing packages, build with warnings as errors, run the whole test
# suite, then again under AddressSanitizer + UndefinedBehaviorSanitizer, then every fuzz target for a
# bounded, fixed amount of work (scripts/fuzz.sh --ci). Safe to re-run.
# Ends with one line "N passed, N failed" (tests over the two builds, and one per fuzz target).
set -uo pipefail
cd "$(dirname "$0")/.."
bash scripts/deps.sh || exit 1
# The build folders: build, build-asan, build-fuzz, or $IC_TEST_BUILD-* to keep a second set apart.
prefix=${IC_TEST_BUILD:-build}
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
# Third stage: every fuzz target of tests/fuzz/ for a fixed amount of work on its seeds (libFuzzer under
# clang, scripts/fuzz.sh --ci: -seed=1 and a fixed -runs each, two at a time, about 3 to 5 minutes on 2
# cores); each target counts as one test, failed by any crash, leak, hang or out-of-memory input.
run_fuzz() {
  echo "== fuzz build ($prefix-fuzz) and bounded runs"
  local log; log=$(mktemp)
  IC_FUZZ_BUILD="$prefix-fuzz" bash scripts/fuzz.sh --ci 2>&1 | tee "$log"
  local n_pass n_fail
  n_pass=$(sed -n 's/^fuzz: \([0-9]*\) passed, \([0-9]*\) failed$/\1/p' "$log" | tail -n1)
  n_fail=$(sed -n 's/^fuzz: \([0-9]*\) passed, \([0-9]*\) failed$/\2/p' "$log" | tail -n1)
  if [ -z "$n_pass" ]; then n_pass=0; n_fail=1; echo "fuzz: no result (build failed?)"; fi
  total_pass=$((total_pass + n_pass)); total_fail=$((total_fail + n_fail))
  rm -f "$log"
}
run_suite release "$prefix" -DCMAKE_BUILD_TYPE=Release
run_suite sanitize "$prefix-asan" -DCMAKE_BUILD_TYPE=RelWithDebInfo -DIC_SANITIZE=ON -DIC_BUILD_BENCH=OFF
run_fuzz
echo "$total_pass passed, $total_fail failed"
[ "$total_fail" -eq 0 ]
