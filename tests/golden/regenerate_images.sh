#!/usr/bin/env bash
# Regenerates the golden images: the bunny (tests/golden/bunny_v1.spg) from
# three views, 240x320 RGB565 and 640x480 RGB888 with the affine projection
# and 240x320 RGB565 with the exact one, drawn by the fixed-point client
# through `stipple render`. For every image that changes it writes
# NAME.diff.png beside it (differing pixels in red) and prints what changed.
# Review the diffs before committing: these bytes are the contract that every
# platform (x86-64, ARM) must reproduce. tests/golden/views.cmake lists the
# same views and sizes for the tests.
#
# usage: tests/golden/regenerate_images.sh [path/to/stipple]
set -euo pipefail
cd "$(dirname "$0")/../.."
S=${1:-build/release/tools/stipple}
views=("yaw0:0,0" "yaw90:90,20" "yaw210:210,35")
configs=("240x320:rgb565:affine" "640x480:rgb888:affine" "240x320:rgb565:exact")
tmp=$(mktemp -d)
trap 'rm -rf "$tmp"' EXIT
for v in "${views[@]}"; do
  for c in "${configs[@]}"; do
    IFS=: read -r size format projection <<<"$c"
    name="bunny_${v%%:*}_${size}_${format}"
    [[ $projection == affine ]] || name+="_$projection"
    "$S" render tests/golden/bunny_v1.spg --camera "${v##*:},3,35" --size "$size" --format "$format" \
      --projection "$projection" -o "$tmp/$name.png" >/dev/null
    golden="tests/golden/$name.png"
    if [[ -f "$golden" ]] && "$S" image-diff "$golden" "$tmp/$name.png" -o "tests/golden/$name.diff.png" >/dev/null; then
      rm -f "tests/golden/$name.diff.png"
      echo "unchanged  $golden"
    else
      [[ -f "$golden" ]] && echo "CHANGED    $golden (see tests/golden/$name.diff.png)" || echo "new        $golden"
      cp "$tmp/$name.png" "$golden"
    fi
  done
done
# The CRC-32 of each image's pixels: what the cross builds' handheld program
# must print (tests/handheld/CMakeLists.txt), checked against the PNGs natively.
# (not the .diff.png files written beside changed images above).
images=()
for f in tests/golden/bunny_yaw*_*.png; do [[ $f == *.diff.png ]] || images+=("$f"); done
"$S" image-crc "${images[@]}" | sed 's|tests/golden/||' > tests/golden/images.crc
echo "wrote tests/golden/images.crc"
