#!/usr/bin/env bash
# What a handheld pays, in instructions a node, to open a .spg version 3
# file (records coded, expanded into the version 2 image) on ARMv5:
# expand_cost.cpp built for ARMv5, run under qemu-user for two passes and
# for one; qemu's block log counts the difference (start-up cancels).
#   tools/bench/expand_cost.sh MODEL_V3.spg
# ARM_CXX (default arm-linux-gnueabi-g++), QEMU (default qemu-arm) and
# QEMU_LD_PREFIX (default /usr/arm-linux-gnueabi) choose the tools.
set -euo pipefail
if [ $# -ne 1 ] || [ "$1" = --help ]; then
  sed -n '2,8p' "$0" | sed 's/^# \{0,1\}//'
  [ "${1:-}" = --help ] && exit 0 || exit 1
fi
model=$1
here=$(cd "$(dirname "${BASH_SOURCE[0]}")" && pwd)
root=$(cd "$here/../.." && pwd)
arm_cxx=${ARM_CXX:-arm-linux-gnueabi-g++} qemu=${QEMU:-qemu-arm}
for tool in "$arm_cxx" "$qemu" awk; do
  command -v "$tool" >/dev/null || { echo "expand_cost.sh: $tool is needed" >&2; exit 1; }
done
work=$(mktemp -d)
trap 'rm -rf "$work"' EXIT
"$arm_cxx" -std=c++20 -O2 -I"$root" -march=armv5te -mfloat-abi=soft -marm -Wno-psabi -DSTIPPLE_HW_DIVIDE=0 \
  -DSTIPPLE_CHECK_RANGES=0 -fno-exceptions -fno-rtti "$here/expand_cost.cpp" "$root"/core/*.cpp -o "$work/arm"
count() {  # instructions of a run of $1 passes
  "$qemu" -L "${QEMU_LD_PREFIX:-/usr/arm-linux-gnueabi}" -d in_asm,exec,nochain -D /dev/stderr \
    "$work/arm" "$model" "$1" 2>&1 >/dev/null | awk -v total=1 -f "$here/qemu_block_log.awk"
}
line=$("$qemu" -L "${QEMU_LD_PREFIX:-/usr/arm-linux-gnueabi}" "$work/arm" "$model" 1)
nodes=$(echo "$line" | sed -n 's/.*: \([0-9]*\) nodes.*/\1/p')
one=$(count 1)
two=$(count 2)
echo "$line; $((two - one)) instructions a pass, $(((two - one) / nodes)) a node"
