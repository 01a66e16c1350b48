#!/usr/bin/env bash
# The desktop's pictures against the scan (docs/viewers.md, "The GL
# client's picture"): for each model and view, `stipple truth` of the scan,
# the software client's default (`stipple render`), the GL client's default
# and its EWA splats (`stipple-gl --headless`, llvmpipe unless a GPU is
# there), each measured with `stipple image-diff` (object PSNR, SSIM) and
# timed (median of five frames; the software client's on one core). Each
# model from three orbit views and a close-up (distance 0.8), with the
# shares of the scan's pixels missing and of the picture's outside it. One
# CSV line a picture on stdout; the pictures under WORKDIR.
# usage: tools/bench/gl_picture.sh BUILD_DIR SHARED_DATA WORKDIR [WxH]
set -euo pipefail
B=$1 DATA=$2 W=$3 SIZE=${4:-640x480}
S=$B/tools/stipple G=$B/tools/stipple-gl
mkdir -p "$W"
measure() {  # truth picture -> "psnr,ssim,missing,outside"
  "$S" image-diff "$1" "$2" --json | python3 -c 'import json,sys; d=json.load(sys.stdin); print("%.2f,%.4f,%.2f,%.2f" % (d["object_psnr_db"], d["ssim"], 100*d["missing"], 100*d["outside_silhouette"]))'
}
echo "model,camera,client,object_psnr_db,ssim,missing_pct,outside_pct,frame_ms"
for model in bunny dragon; do
  [ -s "$W/$model.spg" ] || "$S" encode "$DATA/$model.ply" -o "$W/$model.spg" --quiet >/dev/null
  for camera in 30,20 150,20 260,20 30,20,0.8; do
    "$S" truth "$DATA/$model.ply" --size "$SIZE" --camera "$camera" -o "$W/${model}_${camera}_truth.png" >/dev/null
    out=$("$S" render "$W/$model.spg" --size "$SIZE" --format rgb888 --camera "$camera" --frames 5 -o "$W/${model}_${camera}_software.png")
    ms=$(sed -n 's/.*frame: median \([0-9.]*\) ms.*/\1/p' <<<"$out")
    echo "$model,\"$camera\",software,$(measure "$W/${model}_${camera}_truth.png" "$W/${model}_${camera}_software.png"),$ms"
    for splat in points ewa; do
      out=$("$G" "$W/$model.spg" --headless --size "$SIZE" --camera "$camera" --splat $splat --frames 5 -o "$W/${model}_${camera}_gl_$splat.png")
      ms=$(sed -n 's/.*frame: median \([0-9.]*\) ms.*/\1/p' <<<"$out")
      echo "$model,\"$camera\",gl-$splat,$(measure "$W/${model}_${camera}_truth.png" "$W/${model}_${camera}_gl_$splat.png"),$ms"
    done
  done
done
