"""A frozen engine worker for the cancel tests (stdlib only: it also runs in the GIMP chroot's python3).

It speaks the protocol (docs/protocol.md) as far as a host needs before it
freezes: ``auth``, ``hello`` (with the kit's protocol version, given as the
first argument), ``set_cutout`` (its alpha read and dropped), ``set_camera``,
``edit_ao`` and ``release``; any other command (``render``, ``preview``)
never gets an answer: the worker sleeps, as a worker stuck in a computation
would. It writes its process id to PID_FILE first, so a test can tell whether
it was stopped, and the frozen command's name to PID_FILE.frozen when it
freezes. Over stdio by default; with ``--port 0`` (what
:func:`ssn_engine.host_kit.client.shared_client` appends) it listens on
loopback, prints ``listening HOST:PORT token=TOKEN`` and, as the real
worker does, authenticates every connection at once but serves one at a time.

With ``--stop`` it freezes whole instead (it stops itself, SIGSTOP): nothing
answers any more, not even a new connection's ``auth``, as a worker whose
Python is stuck holding its lock, or a stopped process. Only the first worker
does: one started after a worker froze (PID_FILE.frozen exists) answers the
frozen commands with an error, so the call that started it ends at once.

usage: python3 hung_worker.py PROTOCOL_VERSION PID_FILE [--stop] [--port 0 --idle-timeout S]
"""

import json
import os
import signal
import socket
import sys
import threading
import time

ANSWERED = {"auth", "hello", "set_cutout", "set_camera", "edit_ao", "release"}
WHOLE = "--stop" in sys.argv  # freeze whole (SIGSTOP), the first worker only
AFTER_A_FROZEN_ONE = "a fresh test worker, started after one froze, does not render"


def serve(reader, writer) -> None:
    """Answer requests from ``reader`` on ``writer`` until the stream ends or a request freezes it."""
    while True:
        line = reader.readline()
        if not line:
            return
        header = json.loads(line)
        for entry in header.get("buffers", []):
            reader.read(entry["nbytes"])
        cmd = header.get("cmd")
        reply = {"id": header.get("id"), "ok": True}
        if cmd not in ANSWERED and WHOLE and os.path.exists(sys.argv[2] + ".frozen"):  # another one froze
            reply.update(ok=False, error={"type": "Internal", "message": f"{AFTER_A_FROZEN_ONE} ({cmd})"})
        elif cmd not in ANSWERED:
            with open(sys.argv[2] + ".frozen", "w") as f:
                f.write(str(cmd))
            if WHOLE:
                os.kill(os.getpid(), signal.SIGSTOP)  # frozen whole: not even auth is answered
            time.sleep(3600)  # frozen: no answer
        if cmd == "hello":
            reply.update(protocol=int(sys.argv[1]), version="frozen", method="none")
        elif cmd in ("set_cutout", "set_camera"):
            reply.update(cutout="frozen-cutout")
        writer.write(json.dumps(reply).encode() + b"\n")
        writer.flush()


def converse(conn: socket.socket, slot: threading.Lock) -> None:
    """One loopback connection: its ``auth`` at once, then its requests while it holds the one slot."""
    with conn, conn.makefile("rb") as reader, conn.makefile("wb") as writer:
        try:
            auth = json.loads(reader.readline())
            writer.write(json.dumps({"id": auth.get("id"), "ok": True}).encode() + b"\n")
            writer.flush()
            with slot:
                serve(reader, writer)
        except (OSError, ValueError):
            pass


def main() -> None:
    with open(sys.argv[2], "w") as f:
        f.write(str(os.getpid()))
    if "--port" not in sys.argv:
        serve(sys.stdin.buffer, sys.stdout.buffer)
        return
    server = socket.create_server(("127.0.0.1", 0))
    print(f"listening 127.0.0.1:{server.getsockname()[1]} token=frozen", flush=True)
    slot = threading.Lock()
    while True:
        conn, _ = server.accept()
        threading.Thread(target=converse, args=(conn, slot), daemon=True).start()


if __name__ == "__main__":
    main()
