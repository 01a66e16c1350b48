#!/usr/bin/env bash
# Instructions a frame of the fixed-point client in each kernel variant
# (PointRenderer's table over projection x normals x per-point colour x
# specular, and the lanes), with callgrind: the check that a change to the
# hot path's structure costs nothing, variant by variant. Two binaries give
# two columns and the change; one gives one column.
#   tools/bench/frame_variants.sh MODEL.spg COLOUR_MODEL.spg STIPPLE [STIPPLE_BEFORE]
# e.g. the dragon and rgbd_office, each encoded with stipple encode, against
# a build of the commit before:
#   tools/bench/frame_variants.sh dragon.spg office.spg build/release/tools/stipple /tmp/stipple_before
# Each count is `PointRenderer::render` over `--frames 2` of the default view.
set -euo pipefail
if [ $# -lt 3 ] || [ "$1" = --help ]; then
  sed -n '2,11p' "$0" | sed 's/^# \{0,1\}//'
  [ "${1:-}" = --help ] && exit 0 || exit 1
fi
model=$1 colour=$2
shift 2
work=$(mktemp -d)
trap 'rm -rf "$work"' EXIT
count() {  # STIPPLE MODEL OPTIONS...
  local s=$1 m=$2
  shift 2
  valgrind --tool=callgrind --callgrind-out-file="$work/cg" --toggle-collect='stipple::PointRenderer::render(*)' \
    "$s" render "$m" "$@" --frames 2 -o "$work/frame.png" >/dev/null 2>&1
  callgrind_annotate "$work/cg" | sed -n 's/^ *\([0-9,]*\) .*PROGRAM TOTALS.*/\1/p' | tr -d ,
}
printf '%-16s' variant; for s in "$@"; do printf ' %14s' "$(basename "$s")"; done; [ $# -eq 2 ] && printf ' %9s' change; echo
while IFS='|' read -r name which options; do
  m=$model; [ "$which" = colour ] && m=$colour
  printf '%-16s' "$name"
  counts=()
  for s in "$@"; do
    # shellcheck disable=SC2086
    counts+=("$(count "$s" "$m" $options)")
    printf ' %14s' "${counts[-1]}"
  done
  [ $# -eq 2 ] && awk -v a="${counts[1]}" -v b="${counts[0]}" 'BEGIN { printf " %+8.3f%%", 100 * (b - a) / a }'
  echo
done <<'LIST'
default640|model|--size 640x480 --format rgb888
default240|model|
point|model|--shading point
surface-nospec|model|--no-specular --projection reciprocal
exact|model|--projection exact
scalar|model|--lanes scalar
baseline|model|--lanes baseline
colour|colour|
elevation|model|--color elevation
super2|model|--supersample 2
cap|model|--point-cap 2
LIST
