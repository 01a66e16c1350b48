#!/usr/bin/env bash
# The curvature's sign against the scans (docs/encoder.md "Curvature sign"):
# each scan encoded with and without it (`stipple encode`, `--no-curvature-
# sign`), drawn by the software client with its defaults (surface normals)
# and compared with `stipple truth` of the scan (`stipple image-diff`: object
# PSNR, SSIM); the bunny and the dragon from three orbit views, a close-up and
# a closer look at the dragon's belly, every other scan from its default view.
# Also each file's bytes as version 2 and coded (version 3). One CSV line a
# picture on stdout; the pictures under WORKDIR.
# usage: tools/bench/curvature_sign.sh BUILD_DIR SHARED_DATA WORKDIR [WxH]
set -euo pipefail
B=$1 DATA=$2 W=$3 SIZE=${4:-640x480}
S=$B/tools/stipple
mkdir -p "$W"
measure() {  # truth picture -> "psnr,ssim"
  { "$S" image-diff "$1" "$2" --json || true; } | python3 -c 'import json,sys; d=json.load(sys.stdin); print("%.2f,%.4f" % (d["object_psnr_db"], d["ssim"]))'
}
echo "scan,camera,signed_psnr_db,signed_ssim,unsigned_psnr_db,unsigned_ssim,signed_bytes,unsigned_bytes,signed_coded_bytes,unsigned_coded_bytes"
for ply in "$DATA"/*.ply; do
  scan=$(basename "$ply" .ply)
  [ "$scan" = nan_vertex ] && continue
  bytes=()
  for sign in on off; do
    flag=""; [ $sign = off ] && flag=--no-curvature-sign
    "$S" encode "$ply" -o "$W/${scan}_$sign.spg" --quiet --no-cut-table $flag >/dev/null
    "$S" convert "$W/${scan}_$sign.spg" -o "$W/${scan}_$sign.v3.spg" --format-version 3 >/dev/null
    bytes+=("$(stat -c %s "$W/${scan}_$sign.spg")" "$(stat -c %s "$W/${scan}_$sign.v3.spg")")
  done
  case $scan in
    bunny) cameras="30,20 150,20 260,20 30,20,0.8" ;;
    dragon) cameras="30,20 150,20 260,20 30,20,0.8 120,10,0.5" ;;
    *) cameras="default" ;;
  esac
  for camera in $cameras; do
    cam=(); [ "$camera" != default ] && cam=(--camera "$camera")
    "$S" truth "$ply" --size "$SIZE" "${cam[@]}" -o "$W/${scan}_${camera}_truth.png" >/dev/null
    line="$scan,\"$camera\""
    for sign in on off; do
      "$S" render "$W/${scan}_$sign.spg" --size "$SIZE" --format rgb888 "${cam[@]}" -o "$W/${scan}_${camera}_$sign.png" >/dev/null
      line="$line,$(measure "$W/${scan}_${camera}_truth.png" "$W/${scan}_${camera}_$sign.png")"
    done
    echo "$line,${bytes[0]},${bytes[2]},${bytes[1]},${bytes[3]}"
  done
done
