#!/usr/bin/env bash
# The client's frame cost in instructions, as a fit:
#   instructions per frame = constant + per_node x nodes + per_point x points
# over six frames of one model and camera: the cut at 2 and 3 px (FIT_CUTS
# to choose others: a small model's cut may not change between them), each
# at quality 0.5, 1 and 2 — nodes and points vary independently, so neither
# term flatters the other. Instruction counts are repeatable on a noisy
# machine.
#   tools/bench/frame_fit.sh STIPPLE MODEL.spg [render options...]
# counts `stipple render` with callgrind (PointRenderer::render only), e.g.
# issue 15's measurement (the dragon, 640x480 RGB888, per sampled normal,
# resolve and culling off, the whole cut in the cache):
#   tools/bench/frame_fit.sh build/release/tools/stipple dragon.spg --size 640x480 \
#     --format rgb888 --shading point --resolve off --no-cull --cache 100000
# With QEMU set (e.g. QEMU=qemu-arm), STIPPLE is a cross-built stipple-handheld
# counted by qemu-user's block log (Debian's qemu has no TCG plugins;
# QEMU_LD_PREFIX, default /usr/arm-linux-gnueabi): a frame is the whole
# program's `--frames 2` minus `--frames 1`, e.g.
#   FIT_CUTS="2 12" QEMU=qemu-arm tools/bench/frame_fit.sh \
#     build/armv5/tools/handheld/stipple-handheld tests/golden/bunny_v1.spg
# Prints each frame (cut, quality, nodes, points, instructions) and the fit.
set -euo pipefail
if [ $# -lt 2 ] || [ "$1" = --help ]; then
  sed -n '2,21p' "$0" | sed 's/^# \{0,1\}//'
  [ "${1:-}" = --help ] && exit 0 || exit 1
fi
stipple=$1 model=$2
shift 2
qemu=${QEMU:-}
tool=${qemu:-valgrind}
command -v "$tool" >/dev/null || { echo "frame_fit.sh: $tool is needed" >&2; exit 1; }
work=$(mktemp -d)
trap 'rm -rf "$work"' EXIT
rows=$work/rows
# Guest instructions of a run of $1 frames, options after it: qemu logs each
# translated block's instructions once (in_asm) and, unchained, every run of
# a block (exec, by its host address); the count is the sum over the runs.
# It agrees with a single-step log's line count (-singlestep -d exec) to a
# few hundred instructions a run (the clock reads differ), ten times faster.
qemu_count() {
  local frames=$1
  shift
  "$qemu" -L "${QEMU_LD_PREFIX:-/usr/arm-linux-gnueabi}" -d in_asm,exec,nochain -D /dev/stderr \
    "$stipple" "$model" "$@" --frames "$frames" -o "$work/frame$frames.ppm" 2>&1 >/dev/null | awk -v total=1 -f "$(dirname "${BASH_SOURCE[0]}")/qemu_block_log.awk"
}
for cut in ${FIT_CUTS:-2 3}; do
  for quality in 0.5 1 2; do
    options=("$@" --max-size "$cut" --quality "$quality")
    if [ -n "$qemu" ]; then
      # "MODEL: N nodes, P points, arena ..." from the handheld program
      line=$("$qemu" -L "${QEMU_LD_PREFIX:-/usr/arm-linux-gnueabi}" "$stipple" "$model" "${options[@]}" -o "$work/frame.ppm")
      nodes=$(sed -n 's/.*: \([0-9]*\) nodes, .*/\1/p' <<<"$line")
      points=$(sed -n 's/.* nodes, \([0-9]*\) points.*/\1/p' <<<"$line")
      qemu_count 1 "${options[@]}" >"$work/one" &
      qemu_count 2 "${options[@]}" >"$work/two" &
      wait
      frame=$(($(cat "$work/two") - $(cat "$work/one")))
    else
      json=$("$stipple" render "$model" "${options[@]}" --json -o "$work/frame.png")
      nodes=$(sed -n 's/.*"nodes_drawn": \([0-9]*\).*/\1/p' <<<"$json")
      points=$(sed -n 's/.*"points": \([0-9]*\).*/\1/p' <<<"$json")
      valgrind --tool=callgrind --callgrind-out-file="$work/cg" --toggle-collect='stipple::PointRenderer::render(*)' \
        "$stipple" render "$model" "${options[@]}" --frames 2 -o "$work/frame.png" 2>"$work/log" >/dev/null
      frame=$(($(sed -n 's/.*Collected : \([0-9]*\).*/\1/p' "$work/log") / 2))
    fi
    echo "$cut $quality $nodes $points $frame" >>"$rows"
  done
done
awk '
  { n = $3; p = $4; t = $5; printf "cut %s px, quality %s: %d nodes, %d points, %.2f M instructions\n", $1, $2, n, p, t / 1e6
    m00 += 1; m01 += n; m02 += p; m11 += n * n; m12 += n * p; m22 += p * p; v0 += t; v1 += n * t; v2 += p * t }
  function det(a, b, c, d, e, f, g, h, i) { return a * (e * i - f * h) - b * (d * i - f * g) + c * (d * h - e * g) }
  END {
    D = det(m00, m01, m02, m01, m11, m12, m02, m12, m22)
    if (D * D < 1e-9 * (m11 * m22) * (m11 * m22)) {
      print "fit: nodes and points do not vary independently over these frames; choose other cuts with FIT_CUTS" > "/dev/stderr"
      exit 1
    }
    c = det(v0, m01, m02, v1, m11, m12, v2, m12, m22) / D
    a = det(m00, v0, m02, m01, v1, m12, m02, v2, m22) / D
    b = det(m00, m01, v0, m01, m11, v1, m02, m12, v2) / D
    printf "fit: instructions per frame = %.2f M + %.0f x nodes + %.1f x points\n", c / 1e6, a, b
  }' "$rows"
