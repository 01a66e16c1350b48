#!/usr/bin/env bash
# What an encoder change costs in quality, scan by scan: two `stipple`
# programs (say main's and a branch's, or a worktree build of an older commit)
# encode every scan in ../shared/data, and for each the script prints the
# bytes, the leaves' PSNR (the leaves' points regenerated, one-sided and
# symmetric, `stipple sample --leaves` then `stipple metrics`), the nodes the
# default view's cut sends (`stipple cut`), and the default picture's object
# PSNR against the scan's own picture (`stipple render` against
# `stipple truth`, through `stipple image-diff`), then the differences.
#
# usage: tools/bench/encoder_quality.sh OLD_STIPPLE NEW_STIPPLE [SCAN...]
#
# OLD_ARGS and NEW_ARGS (environment) add encode options to each side: the
# same program in one partition against eight, say,
#   NEW_ARGS="--partition-points 100000" tools/bench/encoder_quality.sh S S
set -euo pipefail
OLD=$1 NEW=$2
shift 2
scans=("$@")
[[ ${#scans[@]} -gt 0 ]] || scans=("$(dirname "$0")"/../../../shared/data/*.ply)
work=$(mktemp -d)
trap 'rm -rf "$work"' EXIT

# name stipple scan -> "bytes psnr_one psnr_sym cut_nodes picture_psnr"
row() {
  local tag=$1 S=$2 scan=$3 out=$work/$1 extra
  if [[ $tag == old ]]; then extra=${OLD_ARGS:-}; else extra=${NEW_ARGS:-}; fi
  # shellcheck disable=SC2086  # the options split as words
  "$S" encode "$scan" -o "$out.spg" -q $extra >/dev/null
  "$S" sample "$out.spg" --leaves -o "$out.ply" >/dev/null
  local metrics cut picture
  metrics=$("$S" metrics "$scan" "$out.ply" --json)
  cut=$("$S" cut "$out.spg" --orbit 1 | sed -n 's/.*cold start \([0-9,]*\) nodes sent.*/\1/p' | tr -d ,)
  [[ -f $work/truth.png ]] || "$S" truth "$scan" -o "$work/truth.png" >/dev/null
  "$S" render "$out.spg" -o "$out.png" >/dev/null
  # image-diff exits 1 when the pictures differ, as they do
  picture=$({ "$S" image-diff "$work/truth.png" "$out.png" || true; } | sed -n 's/.*object PSNR \([0-9.]*\) dB.*/\1/p')
  python3 -c 'import json,sys; d=json.loads(sys.argv[1]); print(sys.argv[2], d["psnr_one_sided_db"], d["psnr_symmetric_db"], sys.argv[3], sys.argv[4])' \
    "$metrics" "$(stat -c %s "$out.spg")" "$cut" "$picture"
}

printf '| scan | bytes old → new | leaves PSNR one-sided old → new (Δ) | symmetric old → new (Δ) | cut nodes old → new (Δ %%) | picture vs truth old → new (Δ) |\n'
printf '|---|---:|---:|---:|---:|---:|\n'
for scan in "${scans[@]}"; do
  rm -f "$work/truth.png"
  row old "$OLD" "$scan" >"$work/old.row"  # a failure stops the script (set -e)
  row new "$NEW" "$scan" >"$work/new.row"
  read -r ob o1 os oc op <"$work/old.row"
  read -r nb n1 ns nc np <"$work/new.row"
  python3 -c '
import sys
name, ob, o1, os_, oc, op, nb, n1, ns, nc, np_ = sys.argv[1:]
print(f"| {name} | {int(ob):,} → {int(nb):,} | {float(o1):.2f} → {float(n1):.2f} ({float(n1) - float(o1):+.2f}) | "
      f"{float(os_):.2f} → {float(ns):.2f} ({float(ns) - float(os_):+.2f}) | "
      f"{int(oc):,} → {int(nc):,} ({100 * (int(nc) - int(oc)) / int(oc):+.1f} %) | "
      f"{float(op):.2f} → {float(np_):.2f} ({float(np_) - float(op):+.2f}) |")' \
    "$(basename "$scan")" "$ob" "$o1" "$os" "$oc" "$op" "$nb" "$n1" "$ns" "$nc" "$np"
done
