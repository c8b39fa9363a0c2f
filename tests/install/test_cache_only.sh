#!/usr/bin/env bash
# test_cache_only.sh BUILD_DIR — the cache alone: configures this source tree with -DIRRCACHE_CACHE_ONLY=ON
# while find_package may not find Embree, assimp, cJSON, OpenEXR, libjpeg or zlib (CMAKE_DISABLE_FIND_PACKAGE_*),
# builds it in a temporary folder (ic_core and irrcache_cache only), then checks its installed package
# with test_install.sh (examples/cache_only.c through find_package and through pkg-config).
# BUILD_DIR, a full build, gives the compiler; skips (77) where test_install.sh would (sanitizer builds).
set -euo pipefail
. "$(dirname "$0")/prologue.sh" cache-only "${1:-}"
here=$(cd "$(dirname "$0")" && pwd)
no_find=()
for pkg in embree assimp cJSON OpenEXR JPEG ZLIB; do no_find+=("-DCMAKE_DISABLE_FIND_PACKAGE_$pkg=ON"); done
echo "== configure and build with -DIRRCACHE_CACHE_ONLY=ON, renderer dependencies not findable"
cmake -S "$src" -B "$tmp/build" -DIRRCACHE_CACHE_ONLY=ON -DIC_WERROR=ON -DCMAKE_BUILD_TYPE=Release \
      -DCMAKE_C_COMPILER="$(cache_var CMAKE_C_COMPILER)" "${no_find[@]}" >"$tmp/configure.log" 2>&1 \
  || { cat "$tmp/configure.log"; exit 1; }
cmake --build "$tmp/build" -j2 >"$tmp/build.log" 2>&1 || { cat "$tmp/build.log"; exit 1; }
built=$(find "$tmp/build" -maxdepth 1 -name '*.a' -printf '%f\n' | sort | tr '\n' ' ')
[ "$built" = "libic_core.a libirrcache_cache.a " ] || { echo "test_cache_only: built $built"; exit 1; }
bash "$here/test_install.sh" "$tmp/build"
