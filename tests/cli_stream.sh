#!/usr/bin/env bash
# stipple serve and stipple render --connect, as a user runs them: a server on
# a free loopback port, a client rendering an orbit through it; the frames
# must equal those rendered from the file through the in-process loopback,
# the first must equal `stipple render` of the same view, and the server
# must log the client's connect, hello, first cut and removal.
# Then the handheld program: --connect draws the CRC it draws from the file.
# usage: cli_stream.sh STIPPLE STIPPLE-HANDHELD MODEL.spg WORKDIR
set -euo pipefail
S=$1 H=$2 MODEL=$3 W=$4
rm -rf "$W" && mkdir -p "$W"
"$S" serve "$MODEL" --tcp 127.0.0.1:0 --once >"$W/serve.out" 2>"$W/serve.err" &
server=$!
trap 'kill $server 2>/dev/null || true' EXIT
for _ in $(seq 100); do grep -q "serving on port" "$W/serve.out" && break; sleep 0.05; done
port=$(sed -n 's/.*serving on port \([0-9]*\)$/\1/p' "$W/serve.out")
[ -n "$port" ] || { echo "the server did not start"; cat "$W/serve.err"; exit 1; }
"$S" render --connect "127.0.0.1:$port" --path orbit:6 -o "$W/tcp"
wait $server
"$S" render "$MODEL" --path orbit:6 -o "$W/loop"
"$S" render "$MODEL" -o "$W/single.png" >/dev/null
for f in "$W"/loop/frame_*.png; do
  "$S" image-diff "$f" "$W/tcp/$(basename "$f")" >/dev/null || { echo "differs over TCP: $(basename "$f")"; exit 1; }
done
"$S" image-diff "$W/single.png" "$W/loop/frame_0000.png" >/dev/null || { echo "frame 0 differs from stipple render"; exit 1; }
[ "$(wc -l <"$W/tcp/frames.log")" -eq 6 ] || { echo "frames.log should have 6 lines"; exit 1; }
for what in "connected" "hello 240x320 rgb565, attributes normals colour coded, cache 30000 nodes" "first cut" "removed after 6 updates"; do
  grep -q "$what" "$W/serve.err" || { echo "the server log lacks '$what'"; cat "$W/serve.err"; exit 1; }
done
"$S" serve "$MODEL" --tcp 127.0.0.1:0 --once >"$W/serve2.out" 2>"$W/serve2.err" &
server=$!
for _ in $(seq 100); do grep -q "serving on port" "$W/serve2.out" && break; sleep 0.05; done
port=$(sed -n 's/.*serving on port \([0-9]*\)$/\1/p' "$W/serve2.out")
remote=$("$H" --connect "127.0.0.1:$port" --camera 90,20 --crc | grep '^crc32')
wait $server
local=$("$H" "$MODEL" --camera 90,20 --crc | grep '^crc32')
[ "$remote" = "$local" ] || { echo "stipple-handheld --connect: $remote, from the file: $local"; exit 1; }
# Without entropy coding (protocol 4's batches): the same picture.
"$S" serve "$MODEL" --tcp 127.0.0.1:0 --once >"$W/serve4.out" 2>"$W/serve4.err" &
server=$!
for _ in $(seq 100); do grep -q "serving on port" "$W/serve4.out" && break; sleep 0.05; done
port=$(sed -n 's/.*serving on port \([0-9]*\)$/\1/p' "$W/serve4.out")
plain=$("$H" --connect "127.0.0.1:$port" --camera 90,20 --crc --no-coding | grep '^crc32')
wait $server
[ "$plain" = "$local" ] || { echo "stipple-handheld --connect --no-coding: $plain, from the file: $local"; exit 1; }
grep -q "attributes normals colour, cache" "$W/serve4.err" || { echo "--no-coding still asked for coding"; cat "$W/serve4.err"; exit 1; }
# The view as it comes: --at writes the frame shown at each time and a log;
# over loopback the view has converged by 2 s, so that frame is the single
# render's.
"$S" serve "$MODEL" --tcp 127.0.0.1:0 --once >"$W/serve3.out" 2>"$W/serve3.err" &
server=$!
for _ in $(seq 100); do grep -q "serving on port" "$W/serve3.out" && break; sleep 0.05; done
port=$(sed -n 's/.*serving on port \([0-9]*\)$/\1/p' "$W/serve3.out")
"$S" render --connect "127.0.0.1:$port" --at 0,2 -o "$W/at" >/dev/null
kill $server 2>/dev/null || true
[ -f "$W/at/at_0s.png" ] && [ -f "$W/at/at_2s.png" ] || { echo "--at did not write at_0s.png and at_2s.png"; ls "$W/at"; exit 1; }
[ "$(wc -l <"$W/at/at.log")" -eq 2 ] || { echo "at.log should have 2 lines"; cat "$W/at/at.log"; exit 1; }
grep -q "^at_2s.png at 2.00 s: nodes [0-9]* points [0-9]* bytes_received [0-9]* converged at " "$W/at/at.log" ||
  { echo "at.log's second line should say when the view converged"; cat "$W/at/at.log"; exit 1; }
"$S" image-diff "$W/single.png" "$W/at/at_2s.png" >/dev/null || { echo "the converged --at frame differs from stipple render"; exit 1; }
echo "6 frames over TCP equal the loopback frames; server log complete; stipple-handheld --connect $remote; --at frames"

