#!/usr/bin/env bash
# Encodes a scan on a Slurm cluster: the plan here (a login node, or wrap
# this script in a job of its own), every partition as one task of a job
# array, and the merge as a job that waits for the whole array.
#
# usage: tools/cluster/slurm_encode.sh SCAN MODEL.spg WORK [ENCODE OPTIONS...]
#
#   WORK     a folder on a file system every node sees (the partitions, the
#            parts, then MODEL.spg's inputs); removed by the merge job when
#            it succeeds
#   options  go to `stipple encode --plan-only` (--memory 8G, --leaf-size ...)
#
# Environment: STIPPLE (the program, default: stipple on PATH), SBATCH_ARGS
# (extra sbatch options for both jobs: --partition=..., --time=...,
# --cpus-per-task=...). Prints the two job ids. The .spg is byte-identical
# to `stipple encode SCAN -o MODEL.spg` with the same options; a failed task
# fails the array, the merge never runs, and `sbatch --array=ID` of the same
# command runs that task again (docs/encoder.md "On a cluster").
set -euo pipefail
if [[ $# -lt 3 || $1 == -h || $1 == --help ]]; then
  sed -n '2,/^set -euo/p' "$0" | sed '$d; s/^# \{0,1\}//'
  exit $(($# < 3))
fi
scan=$1 model=$2 work=$3
shift 3
stipple=${STIPPLE:-stipple}
read -r -a extra <<<"${SBATCH_ARGS:-}"

"$stipple" encode "$scan" --plan-only "$work" --quiet "$@"
jobs=$(grep -vc '^#' "$work/jobs.txt")
array=$(sbatch --parsable "${extra[@]}" --job-name=stipple-part --array="0-$((jobs - 1))" \
  --wrap="'$stipple' encode-part '$work' \$SLURM_ARRAY_TASK_ID")
merge=$(sbatch --parsable "${extra[@]}" --job-name=stipple-merge --dependency="afterok:$array" \
  --wrap="'$stipple' encode --merge '$work' -o '$model' --quiet && rm -rf '$work'")
echo "slurm_encode.sh: $jobs tasks in array job $array; merge job $merge writes $model"
