#!/usr/bin/env bash
# What a user gets from `cmake --install` (docs/install.md): the programs
# in a prefix of their own, `stipple demo` finding its bundled scan there,
# the man pages, and the client library used by a device project through
# find_package(stipple) and through pkg-config — each build drawing the
# same frame as the other.
#   install_test.sh BUILD_DIR WORK_DIR MODEL.spg
set -euo pipefail
build=$1 work=$2 model=$3
here=$(cd "$(dirname "$0")" && pwd)
prefix=$work/prefix
rm -rf "$work" && mkdir -p "$work"
cmake --install "$build" --prefix "$prefix" >"$work/install.log"
for f in bin/stipple bin/stipple-handheld lib/libstipple_core.a lib/libstipple_raster.a include/stipple/raster/client.h \
         include/stipple/core/spg_format.h lib/cmake/stipple/stippleConfig.cmake lib/pkgconfig/stipple.pc \
         share/stipple/bunny.ply; do
  [ -e "$prefix/$f" ] || { echo "install: $f missing"; exit 1; }
done
if command -v help2man >/dev/null; then
  grep -q "encode" "$prefix/share/man/man1/stipple.1" || { echo "install: stipple.1 lacks the commands"; exit 1; }
  grep -q "connect.fR HOST:PORT" "$prefix/share/man/man1/stipple-handheld.1" || { echo "install: stipple-handheld.1 lacks its options"; exit 1; }
fi
# The installed demo, run from elsewhere, encodes the installed scan.
(cd "$work" && "$prefix/bin/stipple" demo --quiet --image demo.png >demo.log)
grep -q "^$prefix/share/stipple/bunny.ply: " "$work/demo.log" || { echo "demo did not use the installed scan:"; cat "$work/demo.log"; exit 1; }
[ -s "$work/demo.png" ]
# A device project, by CMake package...
cmake -S "$here" -B "$work/tiny" -DCMAKE_PREFIX_PATH="$prefix" -DCMAKE_BUILD_TYPE=Release >"$work/tiny.log"
cmake --build "$work/tiny" >>"$work/tiny.log"
by_cmake=$("$work/tiny/tiny" "$model")
# ... and by pkg-config.
c++ -O2 "$here/tiny.cpp" -o "$work/tiny_pc" $(PKG_CONFIG_PATH="$prefix/lib/pkgconfig" pkg-config --cflags --libs stipple)
by_pc=$("$work/tiny_pc" "$model")
echo "find_package: $by_cmake"
echo "pkg-config:   $by_pc"
[ "$by_cmake" = "$by_pc" ] || { echo "the two builds drew different frames"; exit 1; }
echo "install-complete"
