#!/usr/bin/env bash
# stipple trade end to end on a small model, and its CSV consistent: every
# setting present once, every error finite, more points per node (quality)
# never leaves more pixels missing, more supersampling never a lower object
# PSNR without the resolve (with it, within 0.5 dB of no supersampling: the
# resolve takes most of supersampling's gain, docs/results.md), the resolve
# raises it, and the plot written.
# usage: trade_check.sh STIPPLE MODEL.spg SCAN.ply WORKDIR
set -euo pipefail
S=$1 MODEL=$2 SCAN=$3 W=$4
rm -rf "$W"
"$S" trade "$MODEL" --scan "$SCAN" --views 2 --repeat 1 --size 160x120 -o "$W" | tee "$W.out"
grep -q "^knee of the Pareto front: [a-z-]* [^ ]* ([0-9.]* ms, [0-9.]* dB); on the front: " "$W.out" || { echo "no knee named"; exit 1; }
csv=$W/trade.csv
[ -s "$W/trade.png" ] || { echo "no plot"; exit 1; }
rows=$(($(wc -l <"$csv") - 1))
[ "$rows" -ge 37 ] || { echo "expected every setting, got $rows rows"; exit 1; }
awk -F, 'NR > 1 {
  for (i = 9; i <= 13; ++i) if ($i == "" || $i ~ /nan|inf/) { print "row " NR ": column " i " is not finite: " $i; bad = 1 }
  if ($1 == "quality") { if (seen_q && $13 > last_missing + 1e-9) { print "quality " $2 " leaves more pixels missing"; bad = 1 } last_missing = $13; seen_q = 1 }
  if ($1 == "supersample-resolve-off") { if (seen_s && $9 < last_psnr) { print "supersample " $2 " lowers the object PSNR"; bad = 1 } last_psnr = $9; seen_s = 1 }
  if ($1 == "supersample") { if (seen_r && $9 < first_r - 0.5) { print "supersample " $2 " with the resolve loses over 0.5 dB"; bad = 1 } if (!seen_r) first_r = $9; seen_r = 1 }
  if ($1 == "resolve") { if ($2 == "on") on = $9; else if ($9 >= on) { print "the resolve does not raise the object PSNR"; bad = 1 } }
  defaults += $3
} END { if (defaults < 8) { print "the defaults are not marked"; bad = 1 } exit bad }' "$csv"
echo "$rows settings, consistent"
