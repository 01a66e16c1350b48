#!/usr/bin/env bash
# Draco's rate against distortion for a scan, measured the way `stipple rd`
# measures ours: bits per original point (the .drc file) against the PSNR of
# the decoded points against the scan (`stipple metrics`, one-sided as the
# paper's and symmetric), for position quantization from 6 to 14 bits,
# positions only (compare `stipple rd`'s no-normals setting). Writes a CSV
# that `stipple rd --extra` puts on its plot. Needs Debian's `draco` package.
# usage: tools/draco_rd.sh SCAN.ply OUT.csv [path/to/stipple]
set -euo pipefail
SCAN=$1 OUT=$2 S=${3:-build/release/tools/stipple}
command -v draco_encoder >/dev/null || { echo "draco_encoder not found: apt-get install draco"; exit 1; }
tmp=$(mktemp -d)
trap 'rm -rf "$tmp"' EXIT
points=$("$S" metrics "$SCAN" "$SCAN" --json | sed -n 's/.*"original_points": \([0-9]*\).*/\1/p')
echo "setting,bits_per_point,psnr_one_sided_db,psnr_symmetric_db" >"$OUT"
for qp in 6 8 10 12 14; do
  draco_encoder -point_cloud -i "$SCAN" -o "$tmp/x.drc" -qp "$qp" -cl 10 --skip NORMAL >/dev/null
  draco_decoder -i "$tmp/x.drc" -o "$tmp/x.ply" >/dev/null
  bytes=$(stat -c %s "$tmp/x.drc")
  json=$("$S" metrics "$SCAN" "$tmp/x.ply" --json 2>/dev/null)
  one=$(sed -n 's/.*"psnr_one_sided_db": \([0-9.]*\).*/\1/p' <<<"$json")
  sym=$(sed -n 's/.*"psnr_symmetric_db": \([0-9.]*\).*/\1/p' <<<"$json")
  awk -v b="$bytes" -v p="$points" -v o="$one" -v s="$sym" 'BEGIN { printf "draco,%.4f,%s,%s\n", 8 * b / p, o, s }' >>"$OUT"
done
echo "$OUT: Draco at 6..14 position bits, positions only"
