#!/usr/bin/env bash
# Builds and runs every test: the Release build, the ASan + UBSan build, then
# the ARMv5TE soft-float cross build (core, raster and their tests under
# qemu-arm). Exits non-zero on the first failure.
set -euo pipefail
cd "$(dirname "$0")/.."
for preset in release asan armv5; do
  echo "== $preset =="
  cmake --preset "$preset" >/dev/null
  cmake --build --preset "$preset"
  ctest --preset "$preset" -j2
done
