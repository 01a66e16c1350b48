#!/usr/bin/env bash
# Builds and runs every test twice: the Release build, then the ASan + UBSan
# build. Exits non-zero on the first failure.
set -euo pipefail
cd "$(dirname "$0")/.."
for preset in release asan; do
  echo "== $preset =="
  cmake --preset "$preset" >/dev/null
  cmake --build --preset "$preset"
  ctest --preset "$preset" -j2
done
