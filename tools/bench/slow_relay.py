#!/usr/bin/env python3
"""A TCP relay that slows the server -> client direction to a serial line's rate.

usage: tools/bench/slow_relay.py LISTEN_PORT SERVER_PORT [BYTES_PER_SECOND]

Listens on 127.0.0.1:LISTEN_PORT; each connection is relayed to
127.0.0.1:SERVER_PORT, what the server sends paced to BYTES_PER_SECOND
(default 11520: 115,200 baud, 8N1), what the client sends as it comes. For
trying a stream as a handheld on a USB serial line sees it:

  stipple serve dragon.spg --tcp 7391 &
  tools/bench/slow_relay.py 7392 7391 &
  stipple render --connect 127.0.0.1:7392 --at 0.3,1,5,30 -o frames
"""
import socket
import sys
import threading
import time


def pump(source, sink, rate):
    start, moved = time.monotonic(), 0
    try:
        while True:
            data = source.recv(256 if rate else 65536)
            if not data:
                break
            sink.sendall(data)
            moved += len(data)
            if rate:
                due = start + moved / rate
                if due > time.monotonic():
                    time.sleep(due - time.monotonic())
    except OSError:
        pass
    try:
        sink.shutdown(socket.SHUT_WR)
    except OSError:
        pass


def main():
    if len(sys.argv) not in (3, 4) or sys.argv[1] in ('-h', '--help'):
        print(__doc__.strip())
        return 0 if len(sys.argv) == 2 else 2
    listen_port, server_port = int(sys.argv[1]), int(sys.argv[2])
    rate = float(sys.argv[3]) if len(sys.argv) == 4 else 11520.0
    listener = socket.socket()
    listener.setsockopt(socket.SOL_SOCKET, socket.SO_REUSEADDR, 1)
    listener.bind(('127.0.0.1', listen_port))
    listener.listen(8)
    print(f'relaying 127.0.0.1:{listen_port} -> :{server_port}, down at {rate:.0f} B/s', flush=True)
    while True:
        client, _ = listener.accept()
        try:
            server = socket.create_connection(('127.0.0.1', server_port))
        except OSError as e:
            print(f'the server at :{server_port}: {e}', file=sys.stderr, flush=True)
            client.close()
            continue
        threading.Thread(target=pump, args=(client, server, 0), daemon=True).start()
        threading.Thread(target=pump, args=(server, client, rate), daemon=True).start()


if __name__ == '__main__':
    sys.exit(main())
