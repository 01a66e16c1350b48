#!/usr/bin/env bash
# What a client pays, in instructions a node, to decode protocol 5's
# entropy-coded batches instead of protocol 4's compact ones, on ARMv5:
# coded_stream_cost.cpp built for the host records both streams of a model
# (a cold start and 12 orbit steps at 240x320), built for ARMv5 it receives
# each into a node cache, and qemu-user's block log counts a run of two
# passes less a run of one (the program's start-up cancels).
#   tools/bench/coded_stream_cost.sh MODEL.spg
# Prints each stream's bytes, nodes and instructions a pass, and the
# difference a node. CXX (default g++), ARM_CXX (default
# arm-linux-gnueabi-g++), QEMU (default qemu-arm) and QEMU_LD_PREFIX
# (default /usr/arm-linux-gnueabi) choose the tools.
set -euo pipefail
if [ $# -ne 1 ] || [ "$1" = --help ]; then
  sed -n '2,12p' "$0" | sed 's/^# \{0,1\}//'
  [ "${1:-}" = --help ] && exit 0 || exit 1
fi
model=$1
here=$(cd "$(dirname "${BASH_SOURCE[0]}")" && pwd)
root=$(cd "$here/../.." && pwd)
cxx=${CXX:-g++} arm_cxx=${ARM_CXX:-arm-linux-gnueabi-g++} qemu=${QEMU:-qemu-arm}
for tool in "$cxx" "$arm_cxx" "$qemu" awk; do
  command -v "$tool" >/dev/null || { echo "coded_stream_cost.sh: $tool is needed" >&2; exit 1; }
done
work=$(mktemp -d)
trap 'rm -rf "$work"' EXIT
sources=("$here/coded_stream_cost.cpp" "$root"/core/*.cpp)
"$cxx" -std=c++20 -O2 -I"$root" -DSTIPPLE_HW_DIVIDE=1 -DSTIPPLE_CHECK_RANGES=0 "${sources[@]}" -o "$work/host" &
"$arm_cxx" -std=c++20 -O2 -I"$root" -march=armv5te -mfloat-abi=soft -marm -Wno-psabi -DSTIPPLE_HW_DIVIDE=0 \
  -DSTIPPLE_CHECK_RANGES=0 -fno-exceptions -fno-rtti "${sources[@]}" -o "$work/arm" &
wait
"$work/host" record "$model" "$work" >/dev/null
count() {  # instructions of a run: stream, passes
  "$qemu" -L "${QEMU_LD_PREFIX:-/usr/arm-linux-gnueabi}" -d in_asm,exec,nochain -D /dev/stderr \
    "$work/arm" receive "$1" 60000 "$2" 2>&1 >/dev/null | awk -v total=1 -f "$here/qemu_block_log.awk"
}
declare -A per_pass nodes
for s in compact coded; do
  one=$(count "$work/$s.bin" 1)
  two=$(count "$work/$s.bin" 2)
  per_pass[$s]=$((two - one))
  line=$("$qemu" -L "${QEMU_LD_PREFIX:-/usr/arm-linux-gnueabi}" "$work/arm" receive "$work/$s.bin" 60000 1)
  nodes[$s]=$(echo "$line" | sed -n 's/.*: \([0-9]*\) nodes.*/\1/p')
  echo "$s: $line; ${per_pass[$s]} instructions a pass ($((per_pass[$s] / nodes[$s])) a node)"
done
echo "coded less compact: $(((per_pass[coded] - per_pass[compact]) / nodes[coded])) instructions a node"
