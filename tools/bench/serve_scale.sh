#!/usr/bin/env bash
# What one `stipple serve` holds and sustains (docs/serving.md, "Figures"):
# start-up time and memory with no client, memory and answered cameras with
# 100 viewers at 30 Hz and 1,000 at 10 Hz (`stipple load`, on the same
# machine: the load generator takes a share of the cores), and the most
# viewers at 30 Hz with 99 % of their cameras answered, for each worker count.
# usage: tools/bench/serve_scale.sh MODEL.spg [WORKERS ...]   (default: 1 2)
# env: S (the stipple binary, default build/release/tools/stipple), SECONDS_EACH (10)
set -euo pipefail
MODEL=${1:?usage: serve_scale.sh MODEL.spg [WORKERS ...]}
shift
WORKERS=("$@")
[ ${#WORKERS[@]} -gt 0 ] || WORKERS=(1 2)
S=${S:-build/release/tools/stipple}
EACH=${SECONDS_EACH:-10}
ulimit -n "$(ulimit -Hn)" 2>/dev/null || true
W=$(mktemp -d)
trap 'kill $server 2>/dev/null || true; rm -rf "$W"' EXIT

rss_mb() { awk '/VmRSS/ {printf "%.1f", $2 / 1024}' "/proc/$1/status"; }
peak_during() {  # peak RSS of pid $1 while command "${@:2}" runs
  local pid=$1 peak=0
  shift
  "$@" >"$W/load.out" &
  local load=$!
  while kill -0 $load 2>/dev/null; do
    peak=$(awk -v p="$peak" '/VmRSS/ {print ($2 > p ? $2 : p)}' "/proc/$pid/status")
    sleep 0.2
  done
  wait $load
  awk -v p="$peak" 'BEGIN {printf "%.1f", p / 1024}'
}
field() { sed -n "s/.*\"$1\": *\([0-9.e+-]*\).*/\1/p" "$W/load.out"; }

printf "model %s\n" "$MODEL"
printf "%-8s %-10s %-9s | %-34s | %-34s | %s\n" workers "start ms" "idle MB" "100 viewers at 30 Hz: MB, answered, p50/p99 ms" \
  "1000 at 10 Hz: MB, answered, p50/p99 ms" "most at 30 Hz (99 % answered)"
for w in "${WORKERS[@]}"; do
  start=$(date +%s%N)
  "$S" serve "$MODEL" --tcp 127.0.0.1:0 --workers "$w" --per-address 0 --max-clients 5000 >"$W/serve.out" 2>"$W/serve.err" &
  server=$!
  for _ in $(seq 6000); do grep -q "serving on port" "$W/serve.out" && break; sleep 0.01; done
  ready=$(( ($(date +%s%N) - start) / 1000000 ))
  port=$(sed -n 's/.*serving on port \([0-9]*\).*/\1/p' "$W/serve.out")
  idle=$(rss_mb $server)
  m100=$(peak_during $server "$S" load 127.0.0.1:$port "$MODEL" --clients 100 --rate 30 --seconds "$EACH" --json)
  a100=$(field answered_share) p50a=$(field latency_p50_ms) p99a=$(field latency_p99_ms)
  m1000=$(peak_during $server "$S" load 127.0.0.1:$port "$MODEL" --clients 1000 --rate 10 --seconds "$EACH" --json)
  a1000=$(field answered_share) p50b=$(field latency_p50_ms) p99b=$(field latency_p99_ms)
  most=0
  for n in 10 20 30 40 60 80 100 150 200 300 400; do
    "$S" load 127.0.0.1:$port "$MODEL" --clients $n --rate 30 --seconds "$EACH" --json >"$W/load.out"
    awk -v a="$(field answered_share)" 'BEGIN {exit !(a >= 0.99)}' || break
    most=$n
  done
  printf "%-8s %-10s %-9s | %6s MB %5.1f %% %6.1f/%-7.1f | %6s MB %5.1f %% %6.1f/%-7.1f | %s\n" "$w" "$ready" "$idle" \
    "$m100" "$(awk -v a="$a100" 'BEGIN {print 100 * a}')" "$p50a" "$p99a" \
    "$m1000" "$(awk -v a="$a1000" 'BEGIN {print 100 * a}')" "$p50b" "$p99b" "$most"
  kill -INT $server
  wait $server || true
done
