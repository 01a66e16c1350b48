#!/usr/bin/env bash
# Builds and runs every test: the Release build, the ASan + UBSan build, a
# Release build by clang (its warnings; the golden images from a second
# compiler), then the cross builds for ARMv5TE soft-float, ARMv7-A and
# AArch64 (core, raster, the handheld program and their tests under
# qemu-user), then the plain build a user types (CMake's -O3, warnings not
# errors — but any warning fails CI) installed to a prefix, its demo run
# from there (docs/install.md), then fuzzes every libFuzzer harness for FUZZ_SECONDS (60) each
# under ASan + UBSan (.ci/fuzz.sh). Exits non-zero on the first failure.
set -euo pipefail
cd "$(dirname "$0")/.."
for preset in release asan clang armv5 armv7 aarch64; do
  echo "== $preset =="
  cmake --preset "$preset" >/dev/null
  cmake --build --preset "$preset"
  ctest --preset "$preset" -j2
done
echo "== plain: cmake -S . -B build/plain -DCMAKE_BUILD_TYPE=Release =="
cmake -S . -B build/plain -G Ninja -DCMAKE_BUILD_TYPE=Release -DSTIPPLE_BUILD_TESTS=OFF >/dev/null
cmake --build build/plain -j2 2>&1 | tee build/plain.log | grep -E "warning|error" || true
if grep -q "warning:" build/plain.log; then echo "the plain build warns (see above)"; exit 1; fi
rm -rf build/plain-prefix && cmake --install build/plain --prefix build/plain-prefix >/dev/null
(cd build && plain-prefix/bin/stipple demo --quiet --image plain-demo.png)
echo "== fuzz =="
FUZZ_SECONDS=${FUZZ_SECONDS:-60} bash .ci/fuzz.sh
