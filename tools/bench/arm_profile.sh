#!/usr/bin/env bash
# Where an ARM build's frame goes, function by function, from qemu-user's
# single-step execution log (Debian's qemu has no TCG plugins): every guest
# instruction is one logged block, so counting the logged PCs of `--frames 2`
# minus those of `--frames 1` gives one frame's instructions per function.
#   tools/bench/arm_profile.sh HANDHELD MODEL.spg [stipple-handheld options...]
# e.g. (the ARMv5 preset's handheld program on the bunny):
#   tools/bench/arm_profile.sh build/armv5/tools/handheld/stipple-handheld \
#     tests/golden/bunny_v1.spg
# Prints the frame's total and the 20 costliest functions. QEMU (default
# qemu-arm), QEMU_LD_PREFIX (default /usr/arm-linux-gnueabi) and NM (default
# arm-linux-gnueabi-nm) choose the target; the program is a PIE that
# qemu-user loads at 0x40000000 (LOAD_BASE to change). LINES=NAME also
# prints the 25 costliest source lines of the functions whose names contain
# NAME (the innermost inlined line; ADDR2LINE, default
# arm-linux-gnueabi-addr2line) — for a build with debug information, e.g.
# -DCMAKE_CXX_FLAGS_RELEASE="-O2 -g -DNDEBUG".
set -euo pipefail
if [ $# -lt 2 ] || [ "$1" = --help ]; then
  sed -n '2,17p' "$0" | sed 's/^# \{0,1\}//'
  [ "${1:-}" = --help ] && exit 0 || exit 1
fi
program=$1 model=$2
shift 2
qemu=${QEMU:-qemu-arm} prefix=${QEMU_LD_PREFIX:-/usr/arm-linux-gnueabi} nm=${NM:-arm-linux-gnueabi-nm}
base=${LOAD_BASE:-0x40000000}
for tool in "$qemu" "$nm" python3 ${LINES:+"${ADDR2LINE:-arm-linux-gnueabi-addr2line}"}; do
  command -v "$tool" >/dev/null || { echo "arm_profile.sh: $tool is needed" >&2; exit 1; }
done
work=$(mktemp -d)
trap 'rm -rf "$work"' EXIT
histogram() {  # PC counts of a run of $1 frames, options after it
  local frames=$1
  shift
  "$qemu" -L "$prefix" -singlestep -d nochain,exec -D /dev/stderr "$program" "$model" --frames "$frames" "$@" \
    -o "$work/frame$frames.ppm" 2>&1 >/dev/null |
    awk '/^Trace/ { split($4, f, "/"); n[f[2]]++ } END { for (pc in n) print pc, n[pc] }' >"$work/pc$frames"
}
histogram 1 "$@" &
histogram 2 "$@" &
wait
"$nm" -C --defined-only -n -S "$program" | grep -E '^[0-9a-f]+ [0-9a-f]+ [tTwW] ' >"$work/symbols"
python3 - "$work" "$base" "$program" "${LINES:-}" "${ADDR2LINE:-arm-linux-gnueabi-addr2line}" <<'EOF'
import bisect, subprocess, sys
work, base, program, lines, addr2line = sys.argv[1], int(sys.argv[2], 16), sys.argv[3], sys.argv[4], sys.argv[5]
symbols = []
for line in open(f"{work}/symbols"):
    address, size, _, name = line.rstrip("\n").split(" ", 3)
    symbols.append((int(address, 16) + base, int(size, 16), name))
symbols.sort()
starts = [s[0] for s in symbols]
def load(path):
    return {int(pc, 16): int(n) for pc, n in (line.split() for line in open(path))}
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
    out = subprocess.run([addr2line, "-a", "-i", "-e", program], input="".join(f"{pc - base:#x}\n" for pc in pcs),
                         capture_output=True, text=True, check=True).stdout.splitlines()
    where, pc = {}, None
    for line in out:  # each address, then its lines from the innermost inlined call outwards
        if line.startswith("0x"):
            pc = int(line, 16) + base
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
