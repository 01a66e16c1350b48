#!/usr/bin/env bash
# The encoder in partitions from the command line: the same bytes from one
# process, from its jobs run by hand, from a Slurm array (an sbatch that
# runs what it is given, here) and from a Dask cluster of two workers on
# loopback (when python3-distributed is installed); and its faults — a full
# disk, a job that never finished, a part changed — each named, with no .spg
# and no temporary files left.
#
# usage: cli_partitions.sh STIPPLE MAKE_SCAN SOURCE_DIR WORK_DIR [dask]
set -uo pipefail
S=$1 MAKE=$2 SRC=$3 W=$4 WANT_DASK=${5:-}
rm -rf "$W" && mkdir -p "$W" && cd "$W" || exit 1
pids=()
cleanup() { for p in "${pids[@]}"; do kill "$p" 2>/dev/null; done; wait 2>/dev/null; }
trap cleanup EXIT
fail() { echo "FAIL: $*"; exit 1; }
opts=(--partition-points 8000 --quiet)

"$MAKE" --points 60000 -o scan.las >/dev/null || fail "make-scan"
"$S" encode scan.las -o local.spg "${opts[@]}" --json >local.json || fail "local encode"
grep -qE '"partitions": ([2-9]|[1-9][0-9]+),' local.json || fail "not in partitions: $(cat local.json)"
[[ $(ls -A | grep -c stipple-parts) -eq 0 ]] || fail "the local encode left its partitions"

# By hand: plan, jobs in reverse order, merge.
"$S" encode scan.las --plan-only plan "${opts[@]}" >plan.log || fail "plan: $(cat plan.log)"
jobs=$(grep -vc '^#' plan/jobs.txt)
for ((i = jobs - 1; i >= 0; --i)); do "$S" encode-part plan "$i" --threads 1 >/dev/null || fail "job $i"; done
"$S" encode --merge plan -o steps.spg --quiet >/dev/null || fail "merge"
cmp local.spg steps.spg || fail "the jobs run by hand give other bytes"
echo "by hand: $jobs jobs, the same bytes"

# A job that never finished (killed): its part is missing, named with the
# command that makes it; no .spg appears.
mv plan/part-00002.nodes part2.saved
"$S" encode --merge plan -o missing.spg --quiet 2>err.txt && fail "merge without part 2 succeeded"
grep -q "plan/part-00002.nodes: No such file or directory (has its job run? stipple encode-part plan 2)" err.txt ||
  fail "missing part: $(cat err.txt)"
[[ ! -e missing.spg ]] || fail "a failed merge left missing.spg"
# A part changed after its job: refused by its CRC-32.
cp part2.saved plan/part-00002.nodes
printf '\x55' | dd of=plan/part-00002.nodes bs=1 seek=3000 conv=notrunc status=none
"$S" encode --merge plan -o corrupt.spg --quiet 2>err.txt && fail "merge with a corrupt part succeeded"
grep -q "plan/part-00002.nodes: CRC-32 mismatch" err.txt || fail "corrupt part: $(cat err.txt)"
[[ ! -e corrupt.spg ]] || fail "a failed merge left corrupt.spg"
ls plan | grep -q partial && fail "a .partial file was left"
echo "faults: a missing and a corrupt part are named"

# A full disk while the partitions are written (the file size limit stands
# in for it): a clear error, no .spg, no partition folder.
mkdir full
(ulimit -f 64; trap '' XFSZ; exec "$S" encode scan.las -o full/out.spg "${opts[@]}") 2>err.txt &&
  fail "an encode past the size limit succeeded"
grep -q "write failed: File too large" err.txt || fail "disk full: $(cat err.txt)"
[[ -z $(ls -A full) ]] || fail "a failed encode left: $(ls -A full)"
echo "faults: a full disk is named and cleaned up"

# Slurm: sbatch here runs what it is given at once, an array's tasks in turn.
mkdir bin
cat >bin/sbatch <<'EOF'
#!/usr/bin/env bash
array="" wrap=""
for a in "$@"; do
  case $a in --array=*) array=${a#--array=} ;; --wrap=*) wrap=${a#--wrap=} ;; esac
done
if [[ -n $array ]]; then
  for ((i = ${array%-*}; i <= ${array#*-}; ++i)); do SLURM_ARRAY_TASK_ID=$i bash -c "$wrap" >/dev/null || exit 1; done
else
  bash -c "$wrap" >/dev/null || exit 1
fi
echo $((RANDOM + 1000))
EOF
chmod +x bin/sbatch
PATH=$PWD/bin:$PATH STIPPLE=$S bash "$SRC/tools/cluster/slurm_encode.sh" scan.las slurm.spg "$PWD/slurm-work" \
  --partition-points 8000 >slurm.log || fail "slurm_encode.sh: $(cat slurm.log)"
cmp local.spg slurm.spg || fail "the Slurm array gives other bytes"
[[ ! -e slurm-work ]] || fail "the merge job left its work folder"
echo "slurm: $(cat slurm.log)"

[[ $WANT_DASK == dask ]] || exit 0
PY=/usr/bin/python3
$PY -c 'import distributed' 2>/dev/null || fail "python3-distributed is not installed"
dask-scheduler --host 127.0.0.1 --port 0 --no-dashboard --scheduler-file sched.json >sched.log 2>&1 &
pids+=($!)
for _ in $(seq 100); do [[ -s sched.json ]] && break; sleep 0.2; done
[[ -s sched.json ]] || fail "no scheduler: $(cat sched.log)"
for w in 1 2; do
  dask-worker --scheduler-file sched.json --nthreads 1 --no-dashboard --host 127.0.0.1 >"worker$w.log" 2>&1 &
  pids+=($!)
done
# A stipple whose job 3 fails the first time it runs: the driver retries it.
cat >bin/flaky-stipple <<EOF
#!/usr/bin/env bash
if [[ \$1 == encode-part && \$3 == 3 && ! -e $PWD/failed-once ]]; then touch $PWD/failed-once; echo "flaky" >&2; exit 1; fi
exec "$S" "\$@"
EOF
chmod +x bin/flaky-stipple
$PY "$SRC/tools/cluster/dask_encode.py" scan.las -o dask.spg --scheduler-file sched.json --stipple "$PWD/bin/flaky-stipple" \
  --threads 1 --wait-workers 2 -- --partition-points 8000 >dask.log 2>&1 || fail "dask_encode.py: $(cat dask.log)"
[[ -e failed-once ]] || fail "job 3 never failed"
cmp local.spg dask.spg || fail "the Dask jobs give other bytes"
grep -q "jobs on 2 workers" dask.log || fail "not two workers: $(cat dask.log)"
[[ -z $(ls -d stipple-plan.* 2>/dev/null) ]] || fail "the driver left its plan"
echo "dask: $(tail -1 dask.log)"
