#!/usr/bin/env bash
# Fuzzes every target of tests/fuzz/ (tests/fuzz/README.md) for SECONDS each (default 60), one after
# another on one core: configures a clang build with libFuzzer + ASan + UBSan in build-fuzz/ (installs
# clang with apt-get if it is missing), runs each fuzz_<target> on a copy of tests/fuzz/corpus/<target>/
# (the seeds are never changed), prints per target the executions and the crashes, and copies each crash
# input (crash-*, leak-*, timeout-*, oom-*) into tests/fuzz/regress/<target>/, which the normal test suite
# replays (ctest -R fuzz_replay). Exit status 1 if any target found something.
#   bash scripts/fuzz.sh [SECONDS] [TARGET...]
set -uo pipefail
cd "$(dirname "$0")/.."
seconds=${1:-60}
shift || true
case $seconds in '' | *[!0-9]*) echo "usage: scripts/fuzz.sh [SECONDS] [TARGET...]" >&2; exit 2 ;; esac

if ! command -v clang >/dev/null 2>&1; then
  echo "fuzz: installing clang" >&2
  SUDO=""
  if [ "$(id -u)" -ne 0 ]; then SUDO="sudo"; fi
  $SUDO apt-get update -qq && DEBIAN_FRONTEND=noninteractive $SUDO apt-get install -y -qq clang || exit 1
fi
bash scripts/deps.sh || exit 1
build=build-fuzz
if ! cmake -S . -B "$build" -DCMAKE_C_COMPILER=clang -DCMAKE_BUILD_TYPE=RelWithDebInfo -DIC_FUZZ=ON >/dev/null ||
   ! cmake --build "$build" -j"$(nproc)" >"$build/build.log" 2>&1; then
  tail -n 30 "$build/build.log" >&2
  echo "fuzz: build failed (log: $build/build.log)" >&2
  exit 1
fi

if [ $# -gt 0 ]; then
  targets=("$@")
else
  targets=()
  for f in tests/fuzz/fuzz_*.c; do t=${f##*/fuzz_}; targets+=("${t%.c}"); done
fi
work="$build/work"
found=0
printf '%-12s %8s %12s %8s %8s %8s\n' target seconds executions crashes distinct corpus
for t in "${targets[@]}"; do
  exe="$build/tests/fuzz/fuzz_$t"
  if [ ! -x "$exe" ]; then echo "fuzz: no target $t ($exe)" >&2; found=1; continue; fi
  rm -rf "$work/$t"
  mkdir -p "$work/$t/corpus" "$work/$t/artifacts"
  cp tests/fuzz/corpus/"$t"/* "$work/$t/corpus/" 2>/dev/null
  log="$work/$t/fuzz.log"
  # -rss_limit_mb/-malloc_limit_mb: 2 GB; -timeout: an input running 10 s is reported (timeout-*).
  # -print_final_stats gives stat::number_of_executed_units.
  # A crash ends a libFuzzer run: it is restarted on the grown corpus until SECONDS are spent. Each
  # run writes its input under its own prefix; one input is kept per distinct sanitizer SUMMARY line
  # (the same bug found again is counted, not kept).
  start=$(date +%s); execs=0; crashes=0; run=0; seen=""
  while :; do
    left=$((seconds - ($(date +%s) - start)))
    [ "$left" -gt 0 ] || break
    run=$((run + 1))
    TMPDIR="$work/$t" "$exe" "$work/$t/corpus" -max_total_time="$left" -timeout=10 -rss_limit_mb=2048 \
      -malloc_limit_mb=2048 -print_final_stats=1 -artifact_prefix="$work/$t/run$run-" >"$log" 2>&1
    rc=$?
    n=$(sed -n 's/^stat::number_of_executed_units: *\([0-9]*\).*/\1/p' "$log" | tail -n1)
    execs=$((execs + ${n:-0}))
    cat "$log" >>"$work/$t/fuzz-all.log"
    [ "$rc" -eq 0 ] && break
    crashes=$((crashes + 1))
    new=$(ls "$work/$t"/run$run-* 2>/dev/null)
    if [ -z "$new" ]; then
      echo "fuzz: $t stopped (exit $rc) without an input to save; see $work/$t/fuzz-all.log" >&2
      break
    fi
    sig=$(grep -m1 '^SUMMARY: ' "$log" | sed 's/ in *$//')
    if printf '%s\n' "$seen" | grep -qxF -- "$sig"; then
      rm -f $new
    else
      seen=$(printf '%s\n%s' "$seen" "$sig")
      mv $new "$work/$t/artifacts/"
      cp "$log" "$work/$t/artifacts/$(basename "$(echo "$new" | head -n1)").log"
    fi
  done
  nfiles=$(ls "$work/$t/corpus" | wc -l)
  printf '%-12s %8s %12s %8s %8s %8s\n' "$t" "$seconds" "$execs" "$crashes" "$(ls "$work/$t/artifacts" | grep -vc '\.log$')" "$nfiles"
  if ls "$work/$t/artifacts/" | grep -q .; then
    found=1
    mkdir -p "tests/fuzz/regress/$t"
    for a in "$work/$t/artifacts/"*; do
      case $a in *.log) continue ;; esac
      name=$(basename "$a"); name=${name#run*-}
      cp "$a" "tests/fuzz/regress/$t/$name"
      echo "  $t: $(grep -m1 '^SUMMARY: ' "$a.log") -> tests/fuzz/regress/$t/$name (stack: $a.log)"
    done
  fi
done
exit "$found"
