#!/usr/bin/env bash
# stipple serve --serial and the clients' --serial, as a user runs them over
# a null-modem cable — here a linked pair of pseudo-terminals (socat): the
# server on one end, `stipple render --serial` on the other rendering an
# orbit, whose frames must equal those through the in-process loopback; the
# client says goodbye, so the server (--once) logs it and exits. Then
# `stipple-handheld --serial` draws the CRC it draws from the file.
# usage: cli_serial.sh STIPPLE STIPPLE-HANDHELD MODEL.spg WORKDIR
set -euo pipefail
S=$1 H=$2 MODEL=$3 W=$4
rm -rf "$W" && mkdir -p "$W"
pids=()
trap 'kill "${pids[@]}" 2>/dev/null || true' EXIT
socat pty,raw,echo=0,link="$W/server.tty" pty,raw,echo=0,link="$W/client.tty" 2>"$W/socat.err" &
pids+=($!)
for _ in $(seq 100); do [ -e "$W/server.tty" ] && [ -e "$W/client.tty" ] && break; sleep 0.05; done
[ -e "$W/client.tty" ] || { echo "socat made no pty pair"; cat "$W/socat.err"; exit 1; }

serve() {  # a server on the line (and a free TCP port nobody uses)
  "$S" serve "$MODEL" --tcp 127.0.0.1:0 --serial "$W/server.tty" --once >"$W/serve$1.out" 2>"$W/serve$1.err" &
  server=$!
  pids+=($server)
  for _ in $(seq 100); do grep -q "serving on port" "$W/serve$1.out" && break; sleep 0.05; done
  grep -q "serving on port" "$W/serve$1.out" || { echo "the server did not start"; cat "$W/serve$1.err"; exit 1; }
}
finish() {  # the server must leave by itself once its client said goodbye
  for _ in $(seq 100); do kill -0 "$server" 2>/dev/null || break; sleep 0.05; done
  if kill -0 "$server" 2>/dev/null; then echo "the server did not exit after its serial client left"; cat "$W/serve$1.err"; exit 1; fi
  wait "$server"
}

serve 1
"$S" render --serial "$W/client.tty" --path orbit:4 -o "$W/serial"
finish 1
"$S" render "$MODEL" --path orbit:4 -o "$W/loop"
for f in "$W"/loop/frame_*.png; do
  "$S" image-diff "$f" "$W/serial/$(basename "$f")" >/dev/null || { echo "differs over serial: $(basename "$f")"; exit 1; }
done
for what in "connected" "hello 240x320 rgb565" "first cut" "session 1 ended by the client"; do
  grep -q "$what" "$W/serve1.err" || { echo "the server log lacks '$what'"; cat "$W/serve1.err"; exit 1; }
done

serve 2
remote=$("$H" --serial "$W/client.tty" --camera 90,20 --crc | grep '^crc32')
finish 2
local=$("$H" "$MODEL" --camera 90,20 --crc | grep '^crc32')
[ "$remote" = "$local" ] || { echo "stipple-handheld --serial: $remote, from the file: $local"; exit 1; }
echo "4 frames over a serial line equal the loopback frames; the server let its client go; stipple-handheld --serial $remote"
