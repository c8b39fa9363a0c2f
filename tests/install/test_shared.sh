#!/usr/bin/env bash
# test_shared.sh BUILD_DIR — the cache as shared libraries (-DBUILD_SHARED_LIBS=ON, cache only, so that it
# builds in seconds): libic_core.so and libirrcache_cache.so carry the SONAME of the release
# (lib<name>.so.<major>.<minor> while 0.x), export only irrcache's ic_* symbols, and the installed
# package works through find_package and pkg-config (test_install.sh, the examples run against the
# installed .so files). BUILD_DIR, a full build, gives the compiler; skips (77) in a sanitizer build.
set -euo pipefail
. "$(dirname "$0")/prologue.sh" shared "${1:-}"
here=$(cd "$(dirname "$0")" && pwd)
for tool in readelf nm; do
  command -v "$tool" >/dev/null || { echo "test_shared: $tool not found (binutils)"; exit 1; }
done
echo "== configure and build the cache alone with -DBUILD_SHARED_LIBS=ON"
cmake -S "$src" -B "$tmp/build" -DIRRCACHE_CACHE_ONLY=ON -DBUILD_SHARED_LIBS=ON -DIC_WERROR=ON \
      -DCMAKE_BUILD_TYPE=Release -DCMAKE_C_COMPILER="$(cache_var CMAKE_C_COMPILER)" >"$tmp/configure.log" 2>&1 \
  || { cat "$tmp/configure.log"; exit 1; }
cmake --build "$tmp/build" -j2 >"$tmp/build.log" 2>&1 || { cat "$tmp/build.log"; exit 1; }
version=$(sed -n 's/^CMAKE_PROJECT_VERSION:STATIC=//p' "$tmp/build/CMakeCache.txt")
soversion=$(echo "$version" | awk -F. '{ print ($1 == 0) ? $1 "." $2 : $1 }')
for lib in ic_core irrcache_cache; do
  so="$tmp/build/lib$lib.so.$version"
  [ -f "$so" ] || { echo "test_shared: lib$lib.so.$version not built"; ls "$tmp/build"; exit 1; }
  soname=$(readelf -d "$so" | sed -n 's/.*Library soname: \[\(.*\)\]/\1/p')
  [ "$soname" = "lib$lib.so.$soversion" ] || { echo "test_shared: lib$lib's SONAME is '$soname', expected lib$lib.so.$soversion"; exit 1; }
  # Every defined dynamic symbol is irrcache's own.
  foreign=$(nm -D --defined-only "$so" | awk '{ print $3 }' | grep -v '^ic_' || true)
  [ -z "$foreign" ] || { echo "test_shared: lib$lib exports symbols other than ic_*: $foreign"; exit 1; }
  # (grep -q would stop reading early and nm, cut off, fail the pipeline under pipefail.)
  nm -D --defined-only "$so" | grep -c ' ic_' >/dev/null || { echo "test_shared: lib$lib exports nothing"; exit 1; }
  echo "lib$lib.so.$version: SONAME $soname, $(nm -D --defined-only "$so" | wc -l) symbols, all ic_*"
done
# The examples built through pkg-config find the installed .so files at run time by LD_LIBRARY_PATH
# (test_install.sh sets it), those through find_package by the RPATH CMake gives them.
bash "$here/test_install.sh" "$tmp/build"
