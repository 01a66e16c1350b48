#!/usr/bin/env bash
# Draco's rate against distortion for a scan, measured the way `stipple rd`
# measures ours: bits per original point (the .drc file) against the PSNR of
# the decoded points against the scan (`stipple metrics`, one-sided as the
# paper's and symmetric), for every position quantization from 6 to 16 bits
# (fewer settings under-drew Draco's curve by up to 2.4 dB), positions only
# (compare `stipple rd`'s no-normals setting, which drops colour too): the
# scan's x y z are written to a PLY of their own first, since draco_encoder
# cannot skip colour. Writes a CSV that `stipple rd --extra` puts on its
# plot. Needs Debian's `draco` package and python3.
# usage: tools/draco_rd.sh SCAN.ply OUT.csv [path/to/stipple]
set -euo pipefail
SCAN=$1 OUT=$2 S=${3:-build/release/tools/stipple}
command -v draco_encoder >/dev/null || { echo "draco_encoder not found: apt-get install draco"; exit 1; }
tmp=$(mktemp -d)
trap 'rm -rf "$tmp"' EXIT
points=$("$S" metrics "$SCAN" "$SCAN" --json | sed -n 's/.*"original_points": \([0-9]*\).*/\1/p')
# The vertices' x y z alone, as float32 binary PLY (the scans given are PLY).
python3 - "$SCAN" "$tmp/xyz.ply" <<'PY'
import struct, sys
src = open(sys.argv[1], 'rb')
kinds = {'char': 'b', 'uchar': 'B', 'int8': 'b', 'uint8': 'B', 'short': 'h', 'ushort': 'H', 'int16': 'h', 'uint16': 'H',
         'int': 'i', 'uint': 'I', 'int32': 'i', 'uint32': 'I', 'float': 'f', 'float32': 'f', 'double': 'd', 'float64': 'd'}
fmt, props, count, element = None, [], 0, None
while True:
    words = src.readline().decode('ascii', 'replace').split()
    if not words: continue
    if words[0] == 'format': fmt = words[1]
    elif words[0] == 'element':
        element = words[1]
        if element == 'vertex': count = int(words[2])
    elif words[0] == 'property' and element == 'vertex': props.append((words[-1], words[1]))
    elif words[0] == 'end_header': break
names = [n for n, _ in props]
ix = [names.index(a) for a in 'xyz']
out = open(sys.argv[2], 'wb')
out.write(('ply\nformat binary_little_endian 1.0\nelement vertex %d\nproperty float x\nproperty float y\n'
           'property float z\nend_header\n' % count).encode())
if fmt == 'ascii':
    for _ in range(count):
        v = src.readline().split()
        out.write(struct.pack('<3f', *(float(v[i]) for i in ix)))
else:
    rec = struct.Struct(('<' if fmt == 'binary_little_endian' else '>') + ''.join(kinds[t] for _, t in props))
    for _ in range(count):
        v = rec.unpack(src.read(rec.size))
        out.write(struct.pack('<3f', *(v[i] for i in ix)))
PY
echo "setting,bits_per_point,psnr_one_sided_db,psnr_symmetric_db" >"$OUT"
for qp in 6 7 8 9 10 11 12 13 14 15 16; do
  draco_encoder -point_cloud -i "$tmp/xyz.ply" -o "$tmp/x.drc" -qp "$qp" -cl 10 >/dev/null
  draco_decoder -i "$tmp/x.drc" -o "$tmp/x.ply" >/dev/null
  bytes=$(stat -c %s "$tmp/x.drc")
  json=$("$S" metrics "$SCAN" "$tmp/x.ply" --json 2>/dev/null)
  one=$(sed -n 's/.*"psnr_one_sided_db": \([0-9.]*\).*/\1/p' <<<"$json")
  sym=$(sed -n 's/.*"psnr_symmetric_db": \([0-9.]*\).*/\1/p' <<<"$json")
  awk -v b="$bytes" -v p="$points" -v o="$one" -v s="$sym" 'BEGIN { printf "draco,%.4f,%s,%s\n", 8 * b / p, o, s }' >>"$OUT"
done
echo "$OUT: Draco at 6..16 position bits, positions only"
