# prologue.sh — sourced by the install tests (test_*.sh BUILD_DIR): sets `build` (BUILD_DIR, absolute),
# `src` (this source tree), `cache_var NAME` (a value of BUILD_DIR's CMakeCache.txt) and `tmp` (a fresh
# folder removed on exit, named after the test), and skips the test (exit 77) in a sanitizer or fuzzing
# build, whose static libraries cannot be linked without the sanitizer flags on every link line.
# Usage: . "$(dirname "$0")/prologue.sh" NAME BUILD_DIR
ic_test_name=${1:?prologue.sh: NAME BUILD_DIR}
build=$(cd "${2:?usage: $ic_test_name.sh BUILD_DIR}" && pwd)
src=$(cd "$(dirname "${BASH_SOURCE[0]}")/../.." && pwd)
cache_var() { sed -n "s/^$1:[A-Z]*=//p" "$build/CMakeCache.txt"; }
if [ "$(cache_var IC_SANITIZE)" = ON ] || [ "$(cache_var IC_FUZZ)" = ON ]; then
  echo "skipped: a sanitizer build's libraries cannot be linked without -fsanitize (test the Release build)"
  exit 77
fi
tmp=$(mktemp -d "${TMPDIR:-/tmp}/irrcache-$ic_test_name.XXXXXX")
trap 'rm -rf "$tmp"' EXIT
