#!/usr/bin/env bash
# stipple-emulator as a user sees it: a real window (SDL's X11 driver under
# Xvfb) driven by a scripted input sequence — a D-pad press, a stylus drag —
# with screenshots checked to be the window's size and to have changed as the
# input says: nothing while nothing is pressed, the picture after the orbit,
# again after the refinement window is drawn. Then the emulator fed by
# `stipple serve` over TCP draws, headless, the golden image of its view.
# usage: emulator_window.sh STIPPLE-EMULATOR STIPPLE MODEL.spg GOLDEN.png WORKDIR
set -euo pipefail
E=$1 S=$2 MODEL=$3 GOLDEN=$4 W=$5
rm -rf "$W" && mkdir -p "$W"
cat >"$W/script" <<SCRIPT
30 screenshot $W/idle1.png
40 screenshot $W/idle2.png
41 down right
50 up right
80 screenshot $W/orbit.png
81 stylus-down 60 100
83 stylus-move 180 220
85 stylus-up 180 220
110 screenshot $W/window.png
111 quit
SCRIPT
xvfb-run -a -s "-screen 0 1024x1024x24" env SDL_VIDEODRIVER=x11 "$E" "$MODEL" --script "$W/script" >"$W/out" 2>"$W/err" ||
  { echo "the emulator failed under Xvfb"; cat "$W/out" "$W/err"; exit 1; }
cat "$W/out"
crc() { sed -n "s|.*screenshot $W/$1.png \([0-9]*x[0-9]*\), screen crc32 \([0-9a-f]*\)$|\2|p" "$W/out"; }
size() { sed -n "s|.*screenshot $W/$1.png \([0-9]*x[0-9]*\),.*|\1|p" "$W/out"; }
for s in idle1 idle2 orbit window; do
  # The device image at x2: (240 + 2 x 12) x (320 + 2 x 12 + 4 + 18 + 2 + 30 + 6).
  [ "$(size $s)" = "528x784" ] || { echo "screenshot $s is $(size $s), not 528x784"; exit 1; }
  [ -s "$W/$s.png" ] || { echo "no $s.png"; exit 1; }
done
[ "$(crc idle1)" = "$(crc idle2)" ] || { echo "the screen changed while nothing was pressed"; exit 1; }
[ "$(crc idle2)" != "$(crc orbit)" ] || { echo "the D-pad did not turn the view"; exit 1; }
[ "$(crc orbit)" != "$(crc window)" ] || { echo "the stylus drew no refinement window"; exit 1; }

"$S" serve "$MODEL" --tcp 127.0.0.1:0 --once >"$W/serve.out" 2>"$W/serve.err" &
server=$!
trap 'kill $server 2>/dev/null || true' EXIT
for _ in $(seq 100); do grep -q "serving on port" "$W/serve.out" && break; sleep 0.05; done
port=$(sed -n 's/.*serving on port \([0-9]*\)$/\1/p' "$W/serve.out")
[ -n "$port" ] || { echo "the server did not start"; cat "$W/serve.err"; exit 1; }
"$E" --connect "127.0.0.1:$port" --camera 90,20,3,35 --headless -o "$W/connect.png"
wait $server
"$S" image-diff "$GOLDEN" "$W/connect.png"
echo "window $(size idle1): idle, orbit and stylus as scripted; --connect draws the golden image"
