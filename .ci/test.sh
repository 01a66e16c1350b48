#!/usr/bin/env bash
# Builds and runs every test: the Release build, the ASan + UBSan build, a
# Release build by clang (its warnings; the golden images from a second
# compiler), then the cross builds for ARMv5TE soft-float, ARMv7-A and
# AArch64 (core, raster, the handheld program and their tests under
# qemu-user), then fuzzes every libFuzzer harness for FUZZ_SECONDS (60) each
# under ASan + UBSan (.ci/fuzz.sh). Exits non-zero on the first failure.
set -euo pipefail
cd "$(dirname "$0")/.."
for preset in release asan clang armv5 armv7 aarch64; do
  echo "== $preset =="
  cmake --preset "$preset" >/dev/null
  cmake --build --preset "$preset"
  ctest --preset "$preset" -j2
done
echo "== fuzz =="
FUZZ_SECONDS=${FUZZ_SECONDS:-60} bash .ci/fuzz.sh
