#!/usr/bin/env bash
# Where an ARM build's frame goes, function by function, from qemu-user's
# block log (Debian's qemu has no TCG plugins): each translated block's
# instructions are logged once (in_asm) and, unchained, every run of the
# block (exec), so counting each instruction's runs in `--frames 2` minus
# those in `--frames 1` gives one frame's instructions per function.
#   tools/bench/arm_profile.sh HANDHELD MODEL.spg [stipple-handheld options...]
# e.g. (the ARMv5 preset's handheld program on the bunny):
#   tools/bench/arm_profile.sh build/armv5/tools/handheld/stipple-handheld \
#     tests/golden/bunny_v1.spg
# Prints the frame's total and the 20 costliest functions. QEMU (default
# qemu-arm), QEMU_LD_PREFIX (default /usr/arm-linux-gnueabi) and NM (default
# arm-linux-gnueabi-nm) choose the target; the program is a PIE, found where
# qemu-user loaded it (its page log's start_code). LINES=NAME also
# prints the 25 costliest source lines of the functions whose names contain
# NAME (the innermost inlined line; ADDR2LINE, default
# arm-linux-gnueabi-addr2line) — for a build with debug information, e.g.
# -DCMAKE_CXX_FLAGS_RELEASE="-O2 -g -DNDEBUG".
set -euo pipefail
if [ $# -lt 2 ] || [ "$1" = --help ]; then
  sed -n '2,18p' "$0" | sed 's/^# \{0,1\}//'
  [ "${1:-}" = --help ] && exit 0 || exit 1
fi
program=$1 model=$2
shift 2
qemu=${QEMU:-qemu-arm} prefix=${QEMU_LD_PREFIX:-/usr/arm-linux-gnueabi} nm=${NM:-arm-linux-gnueabi-nm}
for tool in "$qemu" "$nm" python3 ${LINES:+"${ADDR2LINE:-arm-linux-gnueabi-addr2line}"}; do
  command -v "$tool" >/dev/null || { echo "arm_profile.sh: $tool is needed" >&2; exit 1; }
done
work=$(mktemp -d)
trap 'rm -rf "$work"' EXIT
# Runs of each instruction (its guest address) in a run of $1 frames,
# options after it, and where the program was loaded (base).
histogram() {
  local frames=$1
  shift
  "$qemu" -L "$prefix" -d page,in_asm,exec,nochain -D /dev/stderr "$program" "$model" --frames "$frames" "$@" \
    -o "$work/frame$frames.ppm" 2>&1 >/dev/null | awk -f "$(dirname "${BASH_SOURCE[0]}")/qemu_block_log.awk" >"$work/pc$frames"
}
histogram 1 "$@" &
histogram 2 "$@" &
wait
"$nm" -C --defined-only -n -S "$program" | grep -E '^[0-9a-f]+ [0-9a-f]+ [tTwW] ' >"$work/symbols"
python3 - "$work" "$program" "${LINES:-}" "${ADDR2LINE:-arm-linux-gnueabi-addr2line}" <<'EOF'
import bisect, subprocess, sys
work, program, lines, addr2line = sys.argv[1], sys.argv[2], sys.argv[3], sys.argv[4]
symbols = []
for line in open(f"{work}/symbols"):
    address, size, _, name = line.rstrip("\n").split(" ", 3)
    symbols.append((int(address, 16), int(size, 16), name))
symbols.sort()
starts = [s[0] for s in symbols]
def load(path):  # addresses within the program (its load base taken off)
    rows = [line.split() for line in open(path)]
    base = int(next(v for k, v in rows if k == "base"), 16)
    return {int(pc, 16) - base: int(n) for pc, n in rows if pc != "base"}
one, two = load(f"{work}/pc1"), load(f"{work}/pc2")
total, outside, per = 0, 0, {}
for pc in one.keys() | two.keys():
    n = two.get(pc, 0) - one.get(pc, 0)
    total += n
    i = bisect.bisect_right(starts, pc) - 1
    if i < 0 or pc >= symbols[i][0] + symbols[i][1]:  # in no function of the program
        outside += n
        continue
    per[symbols[i][2]] = per.get(symbols[i][2], 0) + n
print(f"frame: {total} instructions ({outside} outside the program's functions: shared libraries, PLT)")
for name, n in sorted(per.items(), key=lambda kv: -kv[1])[:20]:
    print(f"{n:>11} {100 * n / total:5.1f} %  {name[:140]}")
if lines:
    pcs = []
    for pc in one.keys() | two.keys():
        i = bisect.bisect_right(starts, pc) - 1
        if i >= 0 and pc < symbols[i][0] + symbols[i][1] and lines in symbols[i][2]:
            pcs.append(pc)
    out = subprocess.run([addr2line, "-a", "-i", "-e", program], input="".join(f"{pc:#x}\n" for pc in pcs),
                         capture_output=True, text=True, check=True).stdout.splitlines()
    where, pc = {}, None
    for line in out:  # each address, then its lines from the innermost inlined call outwards
        if line.startswith("0x"):
            pc = int(line, 16)
        elif pc not in where:
            where[pc] = line
    per_line = {}
    for pc in pcs:
        key = where.get(pc, "??")
        per_line[key] = per_line.get(key, 0) + two.get(pc, 0) - one.get(pc, 0)
    print(f"source lines of the functions named *{lines}*:")
    for key, n in sorted(per_line.items(), key=lambda kv: -kv[1])[:25]:
        print(f"{n:>11}  {key}")
EOF
