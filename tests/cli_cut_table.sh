#!/usr/bin/env bash
# The cut table beside a model (MODEL.spg.cut), as a user meets it: encode
# writes it and says so; cut-table finds it up to date; the server and
# stipple-handheld map it and draw what they draw without it; a corrupt or
# stale one is named, not used, and cut-table writes it again; --check says
# whether it is the model's; encode --no-cut-table writes none.
# usage: cli_cut_table.sh STIPPLE STIPPLE-HANDHELD SCAN WORKDIR
set -euo pipefail
S=$1 H=$2 SCAN=$3 W=$4
rm -rf "$W" && mkdir -p "$W"
fail() { echo "$*"; exit 1; }
"$S" encode "$SCAN" -o "$W/m.spg" -q >"$W/encode.out"
grep -q "cut table $W/m.spg.cut, [0-9,]* bytes" "$W/encode.out" || { cat "$W/encode.out"; fail "encode does not name the table"; }
nodes=$("$S" info "$W/m.spg" --json | sed -n 's/.*"nodes": \([0-9]*\),.*/\1/p')
[ "$(stat -c %s "$W/m.spg.cut")" -eq $((64 + 36 * nodes)) ] || fail "the table is not 64 + 36 bytes a node ($nodes nodes)"
"$S" cut-table "$W/m.spg" | grep -q "m.spg.cut: up to date" || fail "cut-table should find it up to date"
"$S" cut-table "$W/m.spg" --check >/dev/null || fail "--check: the table is the model's"

# Mapped, the handheld draws the picture it draws with the bounds built.
mapped=$("$H" "$W/m.spg" --crc --memory)
grep -q "(cut table mapped)" <<<"$mapped" || { echo "$mapped"; fail "stipple-handheld did not map the table"; }
cp "$W/m.spg.cut" "$W/good.cut"
printf 'x' | dd of="$W/m.spg.cut" bs=1 seek=1000 conv=notrunc 2>/dev/null
built=$("$H" "$W/m.spg" --crc --memory 2>"$W/handheld.err")
grep -q "m.spg.cut: CRC-32 mismatch; the cut's bounds are built in memory" "$W/handheld.err" ||
  { cat "$W/handheld.err"; fail "stipple-handheld should name the corrupt table"; }
grep -q "(cut bounds built)" <<<"$built" || fail "stipple-handheld used a corrupt table"
[ "$(grep '^crc32' <<<"$mapped")" = "$(grep '^crc32' <<<"$built")" ] || fail "mapped and built bounds draw different frames"
if "$S" cut-table "$W/m.spg" --check 2>"$W/check.err"; then fail "--check passed a corrupt table"; fi
grep -q "CRC-32 mismatch" "$W/check.err" || { cat "$W/check.err"; fail "--check should say why"; }

# The server says how its bounds came; cut-table mends the table.
"$S" serve "$W/m.spg" --tcp 127.0.0.1:0 --workers 1 >"$W/serve.out" 2>"$W/serve.err" &
server=$!
trap 'kill $server 2>/dev/null || true' EXIT
for _ in $(seq 100); do grep -q "serving on port" "$W/serve.out" && break; sleep 0.05; done
kill -INT $server; wait $server || true
grep -q "m.spg.cut: CRC-32 mismatch; the cut's bounds are built in memory" "$W/serve.err" ||
  { cat "$W/serve.err"; fail "serve should name the corrupt table"; }
"$S" cut-table "$W/m.spg" | grep -q "m.spg.cut: written" || fail "cut-table should write the table again"
cmp "$W/m.spg.cut" "$W/good.cut" || fail "the table written again differs from encode's"
"$S" serve "$W/m.spg" --tcp 127.0.0.1:0 --workers 1 >"$W/serve2.out" 2>"$W/serve2.err" &
server=$!
for _ in $(seq 100); do grep -q "serving on port" "$W/serve2.out" && break; sleep 0.05; done
kill -INT $server; wait $server || true
grep -q "cut table $W/m.spg.cut mapped" "$W/serve2.err" || { cat "$W/serve2.err"; fail "serve should map the table"; }

# Another cone rule: its own table, made on demand; encode can write none.
if "$S" cut-table "$W/m.spg" --leaf-cone 2 --check 2>"$W/cone.err"; then fail "--check passed a table of another rule"; fi
grep -q "made for another cone rule" "$W/cone.err" || { cat "$W/cone.err"; fail "--check should name the cone rule"; }
"$S" encode "$SCAN" -o "$W/bare.spg" -q --no-cut-table >/dev/null
[ ! -e "$W/bare.spg.cut" ] || fail "--no-cut-table wrote a table"
# A table that cannot be written (a folder in its place) is a warning: the model is whole.
mkdir "$W/blocked.spg.cut"
"$S" encode "$SCAN" -o "$W/blocked.spg" -q >/dev/null 2>"$W/blocked.err" || { cat "$W/blocked.err"; fail "encode failed for want of its table"; }
grep -q "warning: .*blocked.spg.cut.*blocked.spg is whole" "$W/blocked.err" || { cat "$W/blocked.err"; fail "encode should warn of the table"; }
"$H" "$W/blocked.spg" --crc >/dev/null || fail "the model without its table does not draw"
echo "encode wrote the table ($nodes nodes); handheld and serve map it; a corrupt one is named and mended"
