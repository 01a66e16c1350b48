#!/usr/bin/env bash
# The encoder's jobs on a Dask cluster of 1 and 2 local workers against the
# local encode of the same plan (issue 37's figure): wall seconds of each,
# and `cmp` of every result with the local one.
#
# usage: tools/bench/dask_scale.sh SCAN [PARTITION_POINTS]   (default 2000000)
#   STIPPLE=build/release/tools/stipple   THREADS=2 (the cores one host has)
set -euo pipefail
[[ $# -ge 1 && $1 != -h && $1 != --help ]] || { sed -n '2,7p' "$0" | sed 's/^# \{0,1\}//'; exit $(($# < 1)); }
scan=$(realpath "$1") parts=${2:-2000000}
root=$(realpath "$(dirname "$0")/../..")
S=$(realpath "${STIPPLE:-$root/build/release/tools/stipple}") THREADS=${THREADS:-2}
work=$(mktemp -d /tmp/stipple-dask.XXXXXX)
pids=()
trap 'kill "${pids[@]}" 2>/dev/null; wait 2>/dev/null; rm -rf "$work"' EXIT
cd "$work"
seconds() { local t0 t1; t0=$(date +%s.%N); "$@" >/dev/null; t1=$(date +%s.%N); python3 -c "print(f'{$t1 - $t0:.2f}')"; }
echo "local, $THREADS threads: $(seconds "$S" encode "$scan" -o local.spg -q --partition-points "$parts" --threads "$THREADS") s"
for workers in 1 2; do
  rm -f sched.json
  dask-scheduler --host 127.0.0.1 --port 0 --no-dashboard --scheduler-file sched.json >sched.log 2>&1 &
  pids=($!)
  while [[ ! -s sched.json ]]; do sleep 0.2; done
  for ((w = 0; w < workers; ++w)); do
    dask-worker --scheduler-file sched.json --nthreads 1 --no-dashboard --host 127.0.0.1 >"worker$w.log" 2>&1 &
    pids+=($!)
  done
  # The host's cores shared among its workers' jobs.
  t=$(seconds /usr/bin/python3 "$root/tools/cluster/dask_encode.py" "$scan" -o "dask$workers.spg" --scheduler-file sched.json \
    --stipple "$S" --threads $((THREADS / workers > 0 ? THREADS / workers : 1)) --wait-workers "$workers" -- --partition-points "$parts")
  cmp -s local.spg "dask$workers.spg" && same="the same bytes" || same="DIFFERENT BYTES"
  echo "dask, $workers worker(s): $t s, $same"
  kill "${pids[@]}" 2>/dev/null
  wait 2>/dev/null || true
  pids=()
done
