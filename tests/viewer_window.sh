#!/usr/bin/env bash
# A desktop viewer as a user sees it: a real window (SDL's X11 driver under
# Xvfb; for stipple-gl an OpenGL context on Mesa's llvmpipe) driven by a
# scripted input sequence — a few D-pad presses, a stylus drag, R, a mouse
# drag, the wheel, the S key, a click on the lighting key — with screenshots
# checked to be the window's size and to have changed as the input says:
# nothing while nothing is pressed, the picture after the orbit, again after
# the refinement window is drawn, back to the first after R, changed by the
# drag and again by the wheel and by the click; S writes a PNG of the window
# whose path it prints. Then the viewer fed by `stipple serve` over TCP
# draws, headless, what it draws from the file: for the emulator the golden
# image of the view itself.
# usage: viewer_window.sh PROGRAM STIPPLE MODEL.spg WxH X0,Y0,X1,Y1 REFERENCE.png|- WORKDIR
set -euo pipefail
E=$1 S=$2 MODEL=$3 SIZE=$4 DRAG=$5 GOLDEN=$6 W=$7
IFS=, read -r x0 y0 x1 y1 <<<"$DRAG"
rm -rf "$W" && mkdir -p "$W"
cat >"$W/script" <<SCRIPT
30 screenshot $W/idle1.png
40 screenshot $W/idle2.png
41 down right
50 up right
52 press up
60 press left
80 screenshot $W/orbit.png
81 stylus-down $x0 $y0
83 stylus-move $x1 $y1
85 stylus-up $x1 $y1
110 screenshot $W/window.png
112 press reset
140 screenshot $W/reset.png
141 orbit-down $x0 $y0
143 orbit-move $x1 $y0
145 orbit-up $x1 $y1
170 screenshot $W/drag.png
171 wheel 3
200 screenshot $W/wheel.png
201 press screenshot
210 click lighting
230 screenshot $W/click.png
231 quit
SCRIPT
(cd "$W" && xvfb-run -a -s "-screen 0 1024x1024x24" env SDL_VIDEODRIVER=x11 "$E" "$MODEL" --script "$W/script" >"$W/out" 2>"$W/err") ||
  { echo "the emulator failed under Xvfb"; cat "$W/out" "$W/err"; exit 1; }
cat "$W/out"
crc() { sed -n "s|.*screenshot $W/$1.png .*crc32 \([0-9a-f]*\)$|\1|p" "$W/out"; }
size() { sed -n "s|.*screenshot $W/$1.png \([0-9]*x[0-9]*\),.*|\1|p" "$W/out"; }
for s in idle1 idle2 orbit window reset drag wheel click; do
  [ "$(size $s)" = "$SIZE" ] || { echo "screenshot $s is $(size $s), not $SIZE"; exit 1; }
  [ -s "$W/$s.png" ] || { echo "no $s.png"; exit 1; }
done
[ "$(crc idle1)" = "$(crc idle2)" ] || { echo "the screen changed while nothing was pressed"; exit 1; }
[ "$(crc idle2)" != "$(crc orbit)" ] || { echo "the D-pad did not turn the view"; exit 1; }
[ "$(crc orbit)" != "$(crc window)" ] || { echo "the stylus drew no refinement window"; exit 1; }
[ "$(crc reset)" = "$(crc idle1)" ] || { echo "R did not return to the first view"; exit 1; }
[ "$(crc reset)" != "$(crc drag)" ] || { echo "a mouse drag did not orbit"; exit 1; }
[ "$(crc drag)" != "$(crc wheel)" ] || { echo "the wheel did not dolly"; exit 1; }
[ "$(crc wheel)" != "$(crc click)" ] || { echo "a click on the lighting key changed nothing"; exit 1; }
shot=$(sed -n 's|^screenshot \([^ ]*\.png\) ([0-9]*x[0-9]*)$|\1|p' "$W/out")
[ -n "$shot" ] && [ -s "$W/$shot" ] || { echo "the S key wrote no screenshot"; exit 1; }
"$S" image-crc "$W/$shot" >/dev/null

"$S" serve "$MODEL" --tcp 127.0.0.1:0 --once >"$W/serve.out" 2>"$W/serve.err" &
server=$!
trap 'kill $server 2>/dev/null || true' EXIT
for _ in $(seq 100); do grep -q "serving on port" "$W/serve.out" && break; sleep 0.05; done
port=$(sed -n 's/.*serving on port \([0-9]*\)$/\1/p' "$W/serve.out")
[ -n "$port" ] || { echo "the server did not start"; cat "$W/serve.err"; exit 1; }
"$E" --connect "127.0.0.1:$port" --camera 90,20,3,35 --headless -o "$W/connect.png"
wait $server
if [ "$GOLDEN" = "-" ]; then
  GOLDEN=$W/local.png
  "$E" "$MODEL" --camera 90,20,3,35 --headless -o "$GOLDEN"
fi
"$S" image-diff "$GOLDEN" "$W/connect.png"
# Without entropy-coded batches (protocol 4's): the same picture.
"$S" serve "$MODEL" --tcp 127.0.0.1:0 --once >"$W/serve2.out" 2>"$W/serve2.err" &
server=$!
for _ in $(seq 100); do grep -q "serving on port" "$W/serve2.out" && break; sleep 0.05; done
port=$(sed -n 's/.*serving on port \([0-9]*\)$/\1/p' "$W/serve2.out")
[ -n "$port" ] || { echo "the second server did not start"; cat "$W/serve2.err"; exit 1; }
"$E" --connect "127.0.0.1:$port" --camera 90,20,3,35 --headless --no-coding -o "$W/connect_plain.png"
wait $server
"$S" image-diff "$GOLDEN" "$W/connect_plain.png"
echo "window $(size idle1): idle, orbit and stylus as scripted; --connect draws $GOLDEN, coded or not"
