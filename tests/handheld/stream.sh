#!/usr/bin/env bash
# The target's handheld program against a host server, as on the bench with
# a device on the wire: `stipple serve` (built for the host) on loopback TCP
# and on one end of a linked pseudo-terminal pair, stipple-handheld (built
# for the target, run by qemu-user) receiving its nodes over each: it must
# draw the CRC it draws from the file itself.
# usage: stream.sh HOST-STIPPLE "EMULATOR ARGS" STIPPLE-HANDHELD MODEL.spg WORKDIR
set -euo pipefail
S=$1 EMU=$2 H=$3 MODEL=$4 W=$5
[ -x "$S" ] || { echo "no host stipple at $S: build the release preset first (cmake --build --preset release)"; exit 1; }
rm -rf "$W" && mkdir -p "$W"
pids=()
trap 'kill "${pids[@]}" 2>/dev/null || true' EXIT
read -r -a emu <<<"$EMU"
local_crc=$("${emu[@]}" "$H" "$MODEL" --camera 90,20 --crc | grep '^crc32')

# TCP
"$S" serve "$MODEL" --tcp 127.0.0.1:0 --once >"$W/tcp.out" 2>"$W/tcp.err" &
pids+=($!)
for _ in $(seq 100); do grep -q "serving on port" "$W/tcp.out" && break; sleep 0.05; done
port=$(sed -n 's/.*serving on port \([0-9]*\)$/\1/p' "$W/tcp.out")
[ -n "$port" ] || { echo "the server did not start"; cat "$W/tcp.err"; exit 1; }
tcp_crc=$("${emu[@]}" "$H" --connect "127.0.0.1:$port" --camera 90,20 --crc | grep '^crc32')
[ "$tcp_crc" = "$local_crc" ] || { echo "--connect: $tcp_crc, from the file: $local_crc"; cat "$W/tcp.err"; exit 1; }

# Serial
socat pty,raw,echo=0,link="$W/server.tty" pty,raw,echo=0,link="$W/client.tty" 2>"$W/socat.err" &
pids+=($!)
for _ in $(seq 100); do [ -e "$W/server.tty" ] && [ -e "$W/client.tty" ] && break; sleep 0.05; done
[ -e "$W/client.tty" ] || { echo "socat made no pty pair"; cat "$W/socat.err"; exit 1; }
"$S" serve "$MODEL" --tcp 127.0.0.1:0 --serial "$W/server.tty" --once >"$W/serial.out" 2>"$W/serial.err" &
pids+=($!)
for _ in $(seq 100); do grep -q "serving on port" "$W/serial.out" && break; sleep 0.05; done
serial_crc=$("${emu[@]}" "$H" --serial "$W/client.tty" --camera 90,20 --crc | grep '^crc32')
[ "$serial_crc" = "$local_crc" ] || { echo "--serial: $serial_crc, from the file: $local_crc"; cat "$W/serial.err"; exit 1; }
grep -q "session 1 ended by the client" "$W/serial.err" || { echo "the server log lacks the goodbye"; cat "$W/serial.err"; exit 1; }
echo "stipple-handheld on the target, over TCP and serial from a host server: $local_crc"
