#!/usr/bin/env bash
# test_install.sh BUILD_DIR — irrcache as an installed package, the way another project uses it:
#   1. cmake --install BUILD_DIR into a temporary prefix; the installed headers include nothing from src/
#      and the exported targets name no source or build folder;
#   2. examples/ configured with find_package(irrcache) (CMAKE_PREFIX_PATH = the prefix) and built; both
#      examples run, render_scene writes a non-empty image of the Cornell box (cache_only alone in an
#      IRRCACHE_CACHE_ONLY build);
#      the manual page (share/man/man1/irrcache.1) names every option of the installed command, and the
#      documentation is under share/doc/irrcache;
#   3. examples/cache_only.c compiled again with nothing but `pkg-config --cflags --libs irrcache-cache`
#      (and render_scene.c with irrcache.pc), and run.
# Skips (77) in a sanitizer build: its static libraries need the sanitizer runtimes on every link line,
# which an installed package's users do not add.
set -euo pipefail
. "$(dirname "$0")/prologue.sh" install "${1:-}"
cache_only=$(cache_var IRRCACHE_CACHE_ONLY)
for tool in cmake pkg-config cc; do
  command -v "$tool" >/dev/null || { echo "test_install: $tool not found (scripts/deps.sh installs it)"; exit 1; }
done
prefix=$tmp/prefix

echo "== install into $prefix"
cmake --install "$build" --prefix "$prefix" >/dev/null
for f in include/irrcache/cache.h include/irrcache/version.h lib/cmake/irrcache/irrcacheConfig.cmake \
         lib/cmake/irrcache/irrcacheConfigVersion.cmake lib/pkgconfig/irrcache-cache.pc; do
  [ -s "$prefix/$f" ] || { echo "test_install: $f not installed"; exit 1; }
done
if [ "$cache_only" != ON ]; then
  [ -x "$prefix/bin/irrcache" ] || { echo "test_install: bin/irrcache not installed"; exit 1; }
  # The manual page and the documentation; the page names every option the installed command has.
  man1=$prefix/share/man/man1/irrcache.1
  [ -s "$man1" ] && head -n1 "$man1" | grep -q '^\.TH IRRCACHE 1' || { echo "test_install: no manual page"; exit 1; }
  [ -s "$prefix/share/doc/irrcache/README.md" ] && [ -s "$prefix/share/doc/irrcache/docs/scene-format.md" ] ||
    { echo "test_install: documentation not installed"; exit 1; }
  for cmd in render diff points; do
    for opt in $("$prefix/bin/irrcache" "$cmd" --help | grep -o -- '^  --[a-z0-9-]*'); do
      grep -q -- "^  $opt" "$man1" || { echo "test_install: the manual page lacks $cmd $opt"; exit 1; }
    done
  done
  if command -v man >/dev/null; then
    man -l "$man1" 2>"$tmp/man.err" | grep -c 'irradiance' >/dev/null && [ ! -s "$tmp/man.err" ] ||
      { echo "test_install: man -l irrcache.1 failed: $(cat "$tmp/man.err")"; exit 1; }
  fi
  "$prefix/bin/irrcache" --version
fi
# Public headers include only each other and the C library; installed targets point inside the prefix.
if grep -nE '#[[:space:]]*include[[:space:]]*"' "$prefix"/include/irrcache/*.h | grep -v '"irrcache/[a-z_]*\.h"'; then
  echo "test_install: an installed header includes something outside include/irrcache"; exit 1
fi
if grep -lE "$src|$build" "$prefix"/lib/cmake/irrcache/*.cmake "$prefix"/lib/pkgconfig/*.pc; then
  echo "test_install: an installed package file names the source or build folder"; exit 1
fi

echo "== examples/ with find_package(irrcache)"
cmake -S "$src/examples" -B "$tmp/examples" -DCMAKE_BUILD_TYPE=Release -DCMAKE_PREFIX_PATH="$prefix" \
      -DCMAKE_C_FLAGS="-Wall -Wextra -Wpedantic -Werror" >"$tmp/configure.log" 2>&1 \
  || { cat "$tmp/configure.log"; exit 1; }
cmake --build "$tmp/examples" -j2 >"$tmp/build.log" 2>&1 || { cat "$tmp/build.log"; exit 1; }
"$tmp/examples/cache_only"
if [ "$cache_only" != ON ]; then
  [ -x "$tmp/examples/render_scene" ] || { echo "test_install: render_scene was not built"; exit 1; }
  "$tmp/examples/render_scene" "$src/scenes/cornell-box/cornell-box.json" "$tmp/cmake.png" 32
  [ -s "$tmp/cmake.png" ] || { echo "test_install: render_scene wrote no image"; exit 1; }
fi

echo "== examples with pkg-config only"
export PKG_CONFIG_PATH=$prefix/lib/pkgconfig
# A shared install (-DBUILD_SHARED_LIBS=ON, tests/install/test_shared.sh) is found at run time here.
export LD_LIBRARY_PATH="$prefix/lib${LD_LIBRARY_PATH:+:$LD_LIBRARY_PATH}"
# shellcheck disable=SC2046  # the flags are meant to split
cc -std=c11 -Wall -Wextra -Wpedantic -Werror -o "$tmp/cache_only_pc" "$src/examples/cache_only.c" \
   $(pkg-config --cflags --libs irrcache-cache)
"$tmp/cache_only_pc"
if [ "$cache_only" != ON ]; then
  # shellcheck disable=SC2046
  cc -std=c11 -Wall -Wextra -Wpedantic -Werror -o "$tmp/render_scene_pc" "$src/examples/render_scene.c" \
     $(pkg-config --cflags --libs irrcache)
  "$tmp/render_scene_pc" "$src/scenes/cornell-box/cornell-box.json" "$tmp/pkgconfig.png" 32
  [ -s "$tmp/pkgconfig.png" ] || { echo "test_install: render_scene (pkg-config) wrote no image"; exit 1; }
fi
echo "test_install: passed"
