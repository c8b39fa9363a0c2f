#!/usr/bin/env bash
# Fuzzes the targets of tests/fuzz/ (tests/fuzz/README.md) in a clang build with libFuzzer + ASan + UBSan
# (build-fuzz/, or $IC_FUZZ_BUILD; clang and libFuzzer come from scripts/deps.sh). Two modes:
#
#   bash scripts/fuzz.sh [SECONDS] [TARGET...]   explore: each target for SECONDS (default 60), one after
#       another on one core, restarted after each crash until the time is spent; prints per target the
#       executions and the crashes, copies one input per distinct sanitizer report (crash-*, leak-*,
#       timeout-*, oom-*) into tests/fuzz/regress/<target>/ (which the normal test suite replays:
#       ctest -R fuzz_replay); exit status 1 if any target found something.
#   bash scripts/fuzz.sh --ci [TARGET...]        check (scripts/test.sh's third stage): each target for a
#       fixed amount of work, -seed=1 and the -runs of ci_runs below, two at a time; a crash, leak, timeout or out-of-memory input fails that target, its input
#       and stack stay in build-fuzz/work/<target>/ (nothing is copied into the repository). Prints one
#       line per target and then "fuzz: N passed, M failed"; exit status 1 if any failed.
#
# In both, each target starts from a fresh copy of tests/fuzz/corpus/<target>/ (the seeds in the
# repository are never changed).
set -uo pipefail
cd "$(dirname "$0")/.."
mode=explore
if [ "${1:-}" = "--ci" ]; then
  mode=ci
  shift
else
  seconds=${1:-60}
  shift || true
  case $seconds in '' | *[!0-9]*) echo "usage: scripts/fuzz.sh [SECONDS] [TARGET...] | --ci [TARGET...]" >&2; exit 2 ;; esac
fi

# Executions per target in --ci mode, with -seed=1: a fixed amount of work rather than a wall-time
# bound, so that a run finds the same inputs whatever the machine's load (each 5 to 150 s on the
# shared 2-core machine, depending on its load; tests/fuzz/README.md has the measured times).
ci_runs() {
  case $1 in
    cache_file) echo 30000 ;;
    image_exr) echo 35000 ;;
    image_hdr) echo 80000 ;;
    image_pfm) echo 80000 ;;
    image_png) echo 25000 ;;
    mesh_glb) echo 24000 ;;
    mesh_gltf) echo 16000 ;;
    mesh_obj) echo 6000 ;;
    mesh_ply) echo 45000 ;;
    scene_json) echo 50000 ;;
    scene_mitsuba) echo 10000 ;;
    scene_radiance) echo 10000 ;;
    view_radiance) echo 30000 ;;
    *) echo 10000 ;; # a new target: give it its own line once its speed is measured
  esac
}

bash scripts/deps.sh || exit 1
build=${IC_FUZZ_BUILD:-build-fuzz}
mkdir -p "$build"
if ! cmake -S . -B "$build" -DCMAKE_C_COMPILER=clang -DCMAKE_BUILD_TYPE=RelWithDebInfo -DIC_FUZZ=ON >"$build/configure.log" 2>&1 ||
   ! cmake --build "$build" -j"$(nproc)" >"$build/build.log" 2>&1; then
  tail -n 30 "$build/configure.log" "$build/build.log" >&2
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
# Each harness writes every input to a file in a scratch folder of its own (tests/fuzz/fuzz_util.h, made
# under $TMPDIR). On tmpfs that costs no disk I/O: on an ext4 mounted with discard, every rewrite waited
# for the disk and the fuzzers used 40-80 % of their core. Each libFuzzer process gets a folder of its own
# there, removed when it ends (a harness that crashed could not remove its own).
scratch="$work"
if [ -d /dev/shm ] && [ -w /dev/shm ]; then scratch=/dev/shm; fi

# A fresh copy of the target's seeds in $work/$t/corpus/.
fresh_corpus() {
  rm -rf "${work:?}/$1"
  mkdir -p "$work/$1/corpus" "$work/$1/artifacts"
  cp tests/fuzz/corpus/"$1"/* "$work/$1/corpus/" 2>/dev/null
}

if [ "$mode" = ci ]; then
  # One target: its fixed work, then one result line in $work/$t/result.
  ci_target() {
    local t=$1 exe="$build/tests/fuzz/fuzz_$1" runs start rc n secs tmp
    runs=$(ci_runs "$t")
    fresh_corpus "$t"
    if [ ! -x "$exe" ]; then
      echo "FAILED fuzz_$t: no executable $exe" >"$work/$t/result"
      return
    fi
    start=$(date +%s%N)
    # Repeatable: -use_cmp=0, as libFuzzer's mutations from traced comparison operands take values that
    # change from one process to the next (addresses, the scratch folder's random name); -reload=0, as
    # re-reading the corpus folder every second makes the inputs tried depend on timing. With both, two
    # runs of one seed try the same inputs. -timeout=60: generous, so that a loaded machine cannot turn a
    # slow input into a failure, while a hang (the PLY header that looped for ever) still fails.
    # -rss_limit_mb/-malloc_limit_mb: 2 GB.
    tmp=$(mktemp -d "$scratch/irrcache-fuzz-run.XXXXXX")
    TMPDIR="$tmp" "$exe" "$work/$t/corpus" -seed=1 -runs="$runs" -use_cmp=0 -reload=0 -timeout=60 \
      -rss_limit_mb=2048 -malloc_limit_mb=2048 -print_final_stats=1 -artifact_prefix="$work/$t/artifacts/" \
      >"$work/$t/fuzz.log" 2>&1
    rc=$?
    rm -rf "$tmp"
    secs=$((($(date +%s%N) - start) / 1000000000))
    n=$(sed -n 's/^stat::number_of_executed_units: *\([0-9]*\).*/\1/p' "$work/$t/fuzz.log" | tail -n1)
    if [ "$rc" -eq 0 ]; then
      printf 'passed fuzz_%s: %s executions in %s s\n' "$t" "${n:-?}" "$secs" >"$work/$t/result"
    else
      printf 'FAILED fuzz_%s (exit %s after %s s): %s; input: %s; stack: %s\n' "$t" "$rc" "$secs" \
        "$(grep -m1 '^SUMMARY: ' "$work/$t/fuzz.log" || echo 'no sanitizer summary')" \
        "$(ls "$work/$t/artifacts/"* 2>/dev/null | head -n1)" "$work/$t/fuzz.log" >"$work/$t/result"
    fi
  }
  jobs=2
  [ "$(nproc)" -lt 2 ] && jobs=1
  running=0
  for t in "${targets[@]}"; do
    if [ "$running" -ge "$jobs" ]; then
      wait -n
      running=$((running - 1))
    fi
    ci_target "$t" &
    running=$((running + 1))
  done
  wait
  pass=0; fail=0
  for t in "${targets[@]}"; do
    line=$(cat "$work/$t/result" 2>/dev/null || echo "FAILED fuzz_$t: no result")
    echo "$line"
    case $line in passed*) pass=$((pass + 1)) ;; *) fail=$((fail + 1)) ;; esac
  done
  echo "fuzz: $pass passed, $fail failed"
  [ "$fail" -eq 0 ]
  exit
fi

found=0
printf '%-12s %8s %12s %8s %8s %8s\n' target seconds executions crashes distinct corpus
for t in "${targets[@]}"; do
  exe="$build/tests/fuzz/fuzz_$t"
  if [ ! -x "$exe" ]; then echo "fuzz: no target $t ($exe)" >&2; found=1; continue; fi
  fresh_corpus "$t"
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
    tmp=$(mktemp -d "$scratch/irrcache-fuzz-run.XXXXXX")
    TMPDIR="$tmp" "$exe" "$work/$t/corpus" -max_total_time="$left" -timeout=10 -rss_limit_mb=2048 \
      -malloc_limit_mb=2048 -print_final_stats=1 -artifact_prefix="$work/$t/run$run-" >"$log" 2>&1
    rc=$?
    rm -rf "$tmp"
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
