#!/usr/bin/env bash
# stipple serve --serial and the clients' --serial, as a user runs them over
# a null-modem cable — here a linked pair of pseudo-terminals (socat): the
# server on one end, `stipple render --serial` on the other rendering an
# orbit, whose frames must equal those through the in-process loopback; the
# client says goodbye, so the server (--once) logs it and exits. Then
# `stipple-handheld --serial` draws the CRC it draws from the file. Then a
# server without --once on the line: two sessions one after the other, and
# the cable pulled (socat killed: the line hangs up) and plugged back (a new
# pty pair behind the same names) three times, converging each time.
# usage: cli_serial.sh STIPPLE STIPPLE-HANDHELD MODEL.spg WORKDIR
set -euo pipefail
S=$1 H=$2 MODEL=$3 W=$4
rm -rf "$W" && mkdir -p "$W"
pids=()
trap 'kill "${pids[@]}" 2>/dev/null || true' EXIT
plug() {  # a null-modem cable: a linked pty pair behind two names
  rm -f "$W/server.tty" "$W/client.tty"
  socat pty,raw,echo=0,link="$W/server.tty" pty,raw,echo=0,link="$W/client.tty" 2>"$W/socat.err" &
  cable=$!
  pids+=($cable)
  for _ in $(seq 100); do [ -e "$W/server.tty" ] && [ -e "$W/client.tty" ] && break; sleep 0.05; done
  [ -e "$W/client.tty" ] || { echo "socat made no pty pair"; cat "$W/socat.err"; exit 1; }
}
plug

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

# Session after session on one line, and the cable pulled and plugged back.
"$S" serve "$MODEL" --tcp 127.0.0.1:0 --serial "$W/server.tty" >"$W/serve3.out" 2>"$W/serve3.err" &
server=$!
pids+=($server)
for _ in $(seq 100); do grep -q "serving on port" "$W/serve3.out" && break; sleep 0.05; done
for session in 1 2; do
  got=$("$H" --serial "$W/client.tty" --camera 90,20 --crc | grep '^crc32')
  [ "$got" = "$local" ] || { echo "session $session on one line: $got, from the file: $local"; cat "$W/serve3.err"; exit 1; }
done
for round in 1 2 3; do
  kill "$cable"; wait "$cable" 2>/dev/null || true
  for _ in $(seq 100); do [ "$(grep -c "the line hung up" "$W/serve3.err")" -ge "$round" ] && break; sleep 0.05; done
  [ "$(grep -c "the line hung up" "$W/serve3.err")" -ge "$round" ] || { echo "pull $round: no hang-up logged"; cat "$W/serve3.err"; exit 1; }
  plug
  for _ in $(seq 100); do [ "$(grep -c "the line is back" "$W/serve3.err")" -ge "$round" ] && break; sleep 0.05; done
  got=$("$H" --serial "$W/client.tty" --camera 90,20 --crc | grep '^crc32')
  [ "$got" = "$local" ] || { echo "plugged back $round: $got, from the file: $local"; cat "$W/serve3.err"; exit 1; }
done
kill -INT "$server"; wait "$server" || { echo "the server failed on SIGINT"; cat "$W/serve3.err"; exit 1; }
grep -q "stopping (a signal)" "$W/serve3.err" || { echo "the server did not log its stop"; cat "$W/serve3.err"; exit 1; }
echo "4 frames over a serial line equal the loopback frames; the server let its client go; stipple-handheld --serial $remote;"
echo "one line served 5 sessions, 3 of them after the cable was pulled and plugged back"
