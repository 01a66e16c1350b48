#!/usr/bin/env bash
# The client's frame cost in instructions, as a fit:
#   instructions per frame = constant + per_node x nodes + per_point x points
# from callgrind counts of `stipple render` (PointRenderer::render only) over
# six frames of one model and camera: the cut at 2 and 3 px, each at quality
# 0.5, 1 and 2 — nodes and points vary independently, so neither term
# flatters the other. Repeatable on a noisy machine (instruction counts).
#   tools/bench/frame_fit.sh STIPPLE MODEL.spg [render options...]
# e.g. (issue 15's measurement: the dragon, 640x480 RGB888, per sampled
# normal, resolve and culling off, the whole cut in the cache):
#   tools/bench/frame_fit.sh build/release/tools/stipple dragon.spg --size 640x480 \
#     --format rgb888 --shading point --resolve off --no-cull --cache 100000
# Prints each frame (cut, quality, nodes, points, instructions) and the fit;
# STIPPLE_FIT_RUNNER (e.g. "qemu-arm -plugin ...") is not supported: ARM
# counts come from toolchains/README.md's qemu recipe.
set -euo pipefail
if [ $# -lt 2 ] || [ "$1" = --help ]; then
  sed -n '2,15p' "$0" | sed 's/^# \{0,1\}//'
  [ "${1:-}" = --help ] && exit 0 || exit 1
fi
stipple=$1 model=$2
shift 2
command -v valgrind >/dev/null || { echo "frame_fit.sh: valgrind is needed" >&2; exit 1; }
work=$(mktemp -d)
trap 'rm -rf "$work"' EXIT
rows=$work/rows
for cut in 2 3; do
  for quality in 0.5 1 2; do
    json=$("$stipple" render "$model" "$@" --max-size "$cut" --quality "$quality" --json -o "$work/frame.png")
    nodes=$(sed -n 's/.*"nodes_drawn": \([0-9]*\).*/\1/p' <<<"$json")
    points=$(sed -n 's/.*"points": \([0-9]*\).*/\1/p' <<<"$json")
    valgrind --tool=callgrind --callgrind-out-file="$work/cg" --toggle-collect='stipple::PointRenderer::render*' \
      "$stipple" render "$model" "$@" --max-size "$cut" --quality "$quality" --frames 2 -o "$work/frame.png" \
      2>"$work/log" >/dev/null
    total=$(sed -n 's/.*Collected : \([0-9]*\).*/\1/p' "$work/log")
    echo "$cut $quality $nodes $points $((total / 2))" >>"$rows"
  done
done
awk '
  { n = $3; p = $4; t = $5; printf "cut %s px, quality %s: %d nodes, %d points, %.2f M instructions\n", $1, $2, n, p, t / 1e6
    m00 += 1; m01 += n; m02 += p; m11 += n * n; m12 += n * p; m22 += p * p; v0 += t; v1 += n * t; v2 += p * t }
  function det(a, b, c, d, e, f, g, h, i) { return a * (e * i - f * h) - b * (d * i - f * g) + c * (d * h - e * g) }
  END {
    D = det(m00, m01, m02, m01, m11, m12, m02, m12, m22)
    c = det(v0, m01, m02, v1, m11, m12, v2, m12, m22) / D
    a = det(m00, v0, m02, m01, v1, m12, m02, v2, m22) / D
    b = det(m00, m01, v0, m01, m11, v1, m02, m12, v2) / D
    printf "fit: instructions per frame = %.2f M + %.0f x nodes + %.1f x points\n", c / 1e6, a, b
  }' "$rows"
