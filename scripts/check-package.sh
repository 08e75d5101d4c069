#!/usr/bin/env bash
# Installs a built vkas into a temporary prefix and builds tests/package_consumer (a C program) against it:
# with CMake's find_package(vkas) (shared and static library) and with `pkg-config --cflags --libs vkas`.
# Usage: scripts/check-package.sh [build-dir]   (default: build; it must already be built)
set -euo pipefail
root=$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)
build=$(realpath -m "${1:-$root/build}")
jobs=${VKAS_JOBS:-2}
work=$(mktemp -d "${TMPDIR:-/tmp}/vkas-package.XXXXXX")
trap 'rm -rf "$work"' EXIT
prefix="$work/prefix"

echo "-- install $build into a temporary prefix"
cmake --install "$build" --prefix "$prefix" >/dev/null

echo "-- find_package(vkas): configure, build and run tests/package_consumer"
cmake -S "$root/tests/package_consumer" -B "$work/consumer" -DCMAKE_PREFIX_PATH="$prefix" \
  -DCMAKE_BUILD_TYPE=RelWithDebInfo >"$work/configure.log" 2>&1 || { cat "$work/configure.log"; exit 1; }
cmake --build "$work/consumer" -j"$jobs" >"$work/build.log" 2>&1 || { cat "$work/build.log"; exit 1; }
ctest --test-dir "$work/consumer" --output-on-failure

echo "-- pkg-config vkas: compile the consumer with cc"
pcdir=$(dirname "$(find "$prefix" -name vkas.pc -print -quit)")
export PKG_CONFIG_PATH="$pcdir${PKG_CONFIG_PATH:+:$PKG_CONFIG_PATH}"
libdir=$(pkg-config --variable=libdir vkas)
echo "   pkg-config --modversion vkas: $(pkg-config --modversion vkas)"
echo "   pkg-config --cflags --libs vkas: $(pkg-config --cflags --libs vkas)"
cc -std=c11 -Wall -Wextra -Werror -pedantic "$root/tests/package_consumer/main.c" -o "$work/consumer_pc" \
  $(pkg-config --cflags --libs vkas) -Wl,-rpath,"$libdir"
"$work/consumer_pc"
# Static: a directory holding only libvkas.a makes -lvkas pick it; --static adds Libs.private.
mkdir "$work/static-only" && cp "$libdir/libvkas.a" "$work/static-only/"
cc -std=c11 -Wall -Wextra -Werror -pedantic "$root/tests/package_consumer/main.c" -o "$work/consumer_pc_static" \
  $(pkg-config --cflags vkas) -L"$work/static-only" $(pkg-config --static --libs vkas)
if ldd "$work/consumer_pc_static" | grep -q libvkas; then
  echo "check-package: the static build links libvkas.so" >&2
  exit 1
fi
"$work/consumer_pc_static"
echo "-- package check passed"
