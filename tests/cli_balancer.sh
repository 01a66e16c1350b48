#!/usr/bin/env bash
# Serving beyond loopback, as docs/serving.md sets it up: two `stipple serve`
# processes behind HAProxy, which terminates TLS (a self-signed certificate
# made here with openssl); the client end of the TLS link is socat, as a
# viewer's host would run it (the clients speak plain TCP). `stipple render
# --connect` through TLS and the balancer draws what it draws from the file;
# a second and a third session go to the other server and the first again.
# A server bound to every interface says so in its log.
# usage: cli_balancer.sh STIPPLE MODEL.spg WORKDIR
set -euo pipefail
S=$1 MODEL=$2 W=$3
rm -rf "$W" && mkdir -p "$W"
HAPROXY=$(command -v haproxy || ls /usr/sbin/haproxy 2>/dev/null || true)
[ -n "$HAPROXY" ] || { echo "haproxy is not installed (Debian: apt-get install haproxy)"; exit 1; }
pids=()
trap 'kill "${pids[@]}" 2>/dev/null || true' EXIT
free_port() { python3 -c 'import socket; s = socket.socket(); s.bind(("127.0.0.1", 0)); print(s.getsockname()[1])'; }

serve() {  # serve N: a server on a free port, its port in $port
  "$S" serve "$MODEL" --tcp 127.0.0.1:0 --workers 1 --per-address 0 >"$W/serve$1.out" 2>"$W/serve$1.err" &
  pids+=($!)
  for _ in $(seq 100); do grep -q "serving on port" "$W/serve$1.out" && break; sleep 0.05; done
  port=$(sed -n 's/.*serving on port \([0-9]*\).*/\1/p' "$W/serve$1.out")
  [ -n "$port" ] || { echo "server $1 did not start"; cat "$W/serve$1.err"; exit 1; }
}
serve 1; p1=$port
serve 2; p2=$port

openssl req -x509 -newkey rsa:2048 -nodes -keyout "$W/key.pem" -out "$W/cert.pem" -days 2 -subj "/CN=localhost" \
  2>"$W/openssl.err" || { echo "openssl could not make a certificate"; cat "$W/openssl.err"; exit 1; }
cat "$W/cert.pem" "$W/key.pem" >"$W/haproxy.pem"
tls=$(free_port)
cat >"$W/haproxy.cfg" <<EOF
global
  maxconn 1024
defaults
  mode tcp
  timeout connect 2s
  timeout client 60s
  timeout server 60s
  retries 3
  option redispatch
frontend viewers
  bind 127.0.0.1:$tls ssl crt $W/haproxy.pem
  default_backend servers
backend servers
  balance roundrobin
  server s1 127.0.0.1:$p1 check inter 200ms
  server s2 127.0.0.1:$p2 check inter 200ms
EOF
"$HAPROXY" -c -q -f "$W/haproxy.cfg" || { echo "haproxy refused its configuration"; exit 1; }
"$HAPROXY" -db -q -f "$W/haproxy.cfg" 2>"$W/haproxy.err" &
pids+=($!)
plain=$(free_port)
# The viewer's side: plain TCP in, TLS out, the certificate checked.
socat TCP-LISTEN:$plain,bind=127.0.0.1,reuseaddr,fork \
  "OPENSSL:127.0.0.1:$tls,cafile=$W/cert.pem,commonname=localhost,verify=1" 2>"$W/socat.err" &
pids+=($!)
for _ in $(seq 100); do (exec 3<>/dev/tcp/127.0.0.1/$plain) 2>/dev/null && break; sleep 0.05; done

"$S" render "$MODEL" --camera 90,20 -o "$W/local.png" >/dev/null
for session in 1 2 3; do
  "$S" render --connect 127.0.0.1:$plain --camera 90,20 -o "$W/tls$session.png" >/dev/null 2>"$W/render$session.err" ||
    { echo "session $session through TLS failed:"; cat "$W/render$session.err" "$W/socat.err" "$W/haproxy.err"; exit 1; }
  cmp -s "$W/local.png" "$W/tls$session.png" || { echo "session $session through TLS differs from the local render"; exit 1; }
done
for n in 1 2; do
  grep -q "hello 240x320" "$W/serve$n.err" || { echo "server $n was given no session by the balancer"; cat "$W/serve$n.err"; exit 1; }
done
grep -q "listening on 127.0.0.1:$p1\$" "$W/serve1.err" || { echo "a loopback server should not warn"; cat "$W/serve1.err"; exit 1; }

# Bound to every interface: the log says so.
"$S" serve "$MODEL" --tcp 0.0.0.0:0 --workers 1 >"$W/wide.out" 2>"$W/wide.err" &
wide=$!
pids+=($wide)
for _ in $(seq 100); do grep -q "listening on" "$W/wide.err" && break; sleep 0.05; done
grep -q "reachable beyond this machine" "$W/wide.err" || { echo "0.0.0.0 without a warning:"; cat "$W/wide.err"; exit 1; }
echo "3 sessions through TLS (HAProxy) and the balancer equal the local render; both servers served; 0.0.0.0 is pointed out"
