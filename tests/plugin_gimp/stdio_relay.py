"""Stands in for ``python -m ssn_engine serve`` inside the chroot (its own python3, stdlib only).

The spawned-worker test installs the plug-in with an engine.json whose
command runs this script: it relays the plug-in's stdin/stdout to the
worker listening on the host's loopback port, so GIMP exercises the
plug-in's own spawn path (subprocess pipes) against the real worker. It
first authenticates with the worker's token, as a loopback client must.
usage: python3 stdio_relay.py HOST PORT TOKEN
"""

import json
import socket
import sys
import threading

sock = socket.create_connection((sys.argv[1], int(sys.argv[2])))
sock.sendall(json.dumps({"id": 0, "cmd": "auth", "token": sys.argv[3]}).encode() + b"\n")
reply = b""
while not reply.endswith(b"\n"):  # the auth reply has no buffers: one line, not relayed
    reply += sock.recv(1)
if not json.loads(reply)["ok"]:
    sys.exit(f"relay: the worker refused the token: {reply!r}")


def upstream() -> None:
    while True:
        data = sys.stdin.buffer.read1(1 << 16)
        if not data:
            sock.shutdown(socket.SHUT_WR)
            return
        sock.sendall(data)


threading.Thread(target=upstream, daemon=True).start()
while True:
    chunk = sock.recv(1 << 16)
    if not chunk:
        break
    sys.stdout.buffer.write(chunk)
    sys.stdout.buffer.flush()
