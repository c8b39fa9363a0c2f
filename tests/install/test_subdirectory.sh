#!/usr/bin/env bash
# test_subdirectory.sh BUILD_DIR — irrcache taken into another project's build with
# add_subdirectory(irrcache … EXCLUDE_FROM_ALL), in both modes:
#   1. -DIRRCACHE_CACHE_ONLY=ON: examples/cache_only.c links irrcache::cache and runs, and only the cache's
#      libraries were built;
#   2. the full renderer: examples/render_scene.c links irrcache::render and renders the Cornell box.
# In both the embedded irrcache builds no tests or benchmarks (they default to off when it is not the
# top-level project) and sets no build type of the parent's. BUILD_DIR, a full build, gives the compiler;
# skips (77) in sanitizer builds, whose libraries need the sanitizer flags on every link line.
set -euo pipefail
. "$(dirname "$0")/prologue.sh" subdir "${1:-}"
mkdir -p "$tmp/app"
cat > "$tmp/app/CMakeLists.txt" <<CMAKE
cmake_minimum_required(VERSION 3.20)
project(app LANGUAGES C)
add_subdirectory("$src" irrcache EXCLUDE_FROM_ALL)
add_executable(cache_only "$src/examples/cache_only.c")
target_link_libraries(cache_only PRIVATE irrcache::cache)
if(TARGET irrcache::render)
  add_executable(render_scene "$src/examples/render_scene.c")
  target_link_libraries(render_scene PRIVATE irrcache::render)
endif()
CMAKE
for mode in cache-only full; do
  echo "== add_subdirectory, $mode"
  flags=(-DCMAKE_C_COMPILER="$(cache_var CMAKE_C_COMPILER)" -DCMAKE_BUILD_TYPE=Release)
  [ $mode = cache-only ] && flags+=(-DIRRCACHE_CACHE_ONLY=ON)
  out=$tmp/build-$mode
  cmake -S "$tmp/app" -B "$out" "${flags[@]}" >"$tmp/configure.log" 2>&1 || { cat "$tmp/configure.log"; exit 1; }
  for v in IC_BUILD_TESTS IC_BUILD_BENCH; do
    [ "$(sed -n "s/^$v:[A-Z]*=//p" "$out/CMakeCache.txt")" = OFF ] ||
      { echo "test_subdirectory: $v is not off in an embedded irrcache"; exit 1; }
  done
  cmake --build "$out" -j2 >"$tmp/build.log" 2>&1 || { cat "$tmp/build.log"; exit 1; }
  [ ! -e "$out/irrcache/tests" ] || { echo "test_subdirectory: the embedded irrcache configured its tests"; exit 1; }
  "$out/cache_only" | grep -c 'records' >/dev/null || { echo "test_subdirectory: cache_only did not run"; exit 1; }
  if [ $mode = cache-only ]; then
    [ ! -e "$out/render_scene" ] || { echo "test_subdirectory: the renderer was built in cache-only mode"; exit 1; }
    built=$(find "$out/irrcache" -maxdepth 1 -name '*.a' -printf '%f\n' | sort | tr '\n' ' ')
    [ "$built" = "libic_core.a libirrcache_cache.a " ] || { echo "test_subdirectory: built $built"; exit 1; }
  else
    "$out/render_scene" "$src/scenes/cornell-box/cornell-box.json" "$tmp/sub.png" 16
    [ -s "$tmp/sub.png" ] || { echo "test_subdirectory: render_scene wrote no image"; exit 1; }
  fi
done
echo "test_subdirectory: passed"
