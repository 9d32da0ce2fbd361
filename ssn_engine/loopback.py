"""The engine worker on a loopback TCP socket (``ssn-shadow serve --port``; docs/protocol.md).

Any local program can connect to 127.0.0.1, so a connection's first line must be ``auth`` with the worker's
per-start token, within :data:`AUTH_TIMEOUT` seconds; anything else gets an ``Unauthorized`` reply and the
connection is closed. Connections authenticate on threads of their own, so one that sends nothing, or half a
header, never holds the worker: the authenticated ones are served one at a time, in the order they
authenticated, by one :class:`~ssn_engine.worker.Worker`.
"""

from __future__ import annotations

import contextlib
import hmac
import queue
import secrets
import socket
import sys
import threading
import time
from typing import Any

from .methods import LoadedMethod
from .host_kit.protocol import ProtocolError, encode_header, parse_header
from .worker import Worker, tune_malloc

__all__ = ["AUTH_TIMEOUT", "authenticate", "serve_tcp"]

AUTH_TIMEOUT = 5.0  # seconds a new connection has to send its auth line
MAX_AUTH_LINE = 4096  # bytes: an auth line is far shorter; a longer first line is refused unread
LINGER = 1.0  # seconds a refused connection's input is read and dropped before it is closed
MAX_AUTHENTICATING = 64  # connections authenticating at once; further ones are closed at once


def _first_line(conn: socket.socket, deadline: float) -> bytes:
    """The connection's first line, read a byte at a time (nothing after it is taken from the socket) until
    ``deadline`` (time.monotonic): b"" where the peer closed first; TimeoutError past the deadline."""
    line = bytearray()
    while not line.endswith(b"\n") and len(line) <= MAX_AUTH_LINE:
        left = deadline - time.monotonic()
        if left <= 0:
            raise TimeoutError(f"no auth line within {AUTH_TIMEOUT:g} s")
        conn.settimeout(left)
        byte = conn.recv(1)
        if not byte:
            return b""
        line += byte
    return bytes(line)


def authenticate(conn: socket.socket, token: str) -> bool:
    """Read a new connection's first request: True, after an ``ok`` reply, where it is ``auth`` with ``token``
    (and no buffers); else False, after an ``Unauthorized`` reply where the peer still listens. Never raises."""
    try:
        line = _first_line(conn, time.monotonic() + AUTH_TIMEOUT)
    except TimeoutError:
        return _refuse(conn, None, f"this worker needs its token: send auth within {AUTH_TIMEOUT:g} s")
    except OSError:
        return False
    if not line:
        return False
    try:
        header, specs = parse_header(line)
    except ProtocolError:
        header, specs = {}, []
    given = header.get("token")
    if (
        header.get("cmd") != "auth"
        or specs
        or not isinstance(given, str)
        or not hmac.compare_digest(given.encode("utf-8", "surrogatepass"), token.encode())
    ):
        return _refuse(conn, header.get("id"), "this worker needs its token: send auth first")
    try:
        conn.sendall(encode_header({"id": header.get("id"), "ok": True}))
    except OSError:
        return False
    return True


def _refuse(conn: socket.socket, rid: Any, message: str) -> bool:
    """An ``Unauthorized`` reply, where the peer still listens, then the end of what it sent (for at most
    :data:`LINGER` seconds): a socket closed with unread input resets the connection, which can lose the
    reply before the peer reads it. False."""
    error = {"type": "Unauthorized", "message": message}
    with contextlib.suppress(OSError):
        conn.sendall(encode_header({"id": rid, "ok": False, "error": error}))
        conn.shutdown(socket.SHUT_WR)
        deadline = time.monotonic() + LINGER
        while (left := deadline - time.monotonic()) > 0:
            conn.settimeout(left)
            if not conn.recv(1 << 16):
                break
    return False


def _admit(server: socket.socket, token: str, ready: queue.Queue[socket.socket]) -> None:
    """Accept connections until the server socket is shut down; each authenticates on a thread of its own
    and, once it has, waits in ``ready`` for the worker."""
    slots = threading.BoundedSemaphore(MAX_AUTHENTICATING)

    def handshake(conn: socket.socket) -> None:
        try:
            if authenticate(conn, token):
                ready.put(conn)
            else:
                conn.close()
        finally:
            slots.release()

    while True:
        try:
            conn, _ = server.accept()
        except OSError:  # shut down: the worker is exiting
            return
        if slots.acquire(blocking=False):
            threading.Thread(target=handshake, args=(conn,), daemon=True).start()
        else:
            conn.close()


def _converse(worker: Worker, conn: socket.socket, idle_timeout: float | None) -> bool:
    """Serve one authenticated connection; True where it asked the worker to shut down."""
    conn.settimeout(idle_timeout)
    with conn, conn.makefile("rb") as reader, conn.makefile("wb") as writer:
        try:
            return worker.serve(reader, writer)
        except OSError as exc:  # TimeoutError included: an idle client
            print(f"connection dropped: {exc}", file=sys.stderr, flush=True)
            return False


def serve_tcp(
    loaded: LoadedMethod,
    port: int = 0,
    announce: Any = None,
    token: str | None = None,
    idle_timeout: float | None = None,
) -> None:
    """Serve authenticated connections, one at a time, on 127.0.0.1:``port``.

    Parameters
    ----------
    loaded
        The method the worker renders with.
    port
        The port to listen on; 0 picks a free one.
    announce
        Where the first line goes (default stdout): ``listening 127.0.0.1:PORT token=TOKEN``.
    token
        The token each connection's ``auth`` must carry (default: a random one for this start).
    idle_timeout
        Seconds: the worker exits when no connection authenticates for that long, and drops an authenticated
        connection that sends nothing for that long (default: never).
    """
    tune_malloc()
    worker = Worker(loaded)
    token = token or secrets.token_urlsafe(24)
    ready: queue.Queue[socket.socket] = queue.Queue()
    with socket.create_server(("127.0.0.1", port)) as server:
        bound = server.getsockname()
        print(f"listening {bound[0]}:{bound[1]} token={token}", file=announce or sys.stdout, flush=True)
        admitting = threading.Thread(target=_admit, args=(server, token, ready), daemon=True)
        admitting.start()
        try:
            while True:
                try:
                    conn = ready.get(timeout=idle_timeout)
                except queue.Empty:
                    print(f"no connection for {idle_timeout:g} s: exiting", file=sys.stderr, flush=True)
                    return
                if _converse(worker, conn, idle_timeout):
                    return
        finally:
            with contextlib.suppress(OSError):  # Linux: wakes the accepting thread (closing the socket may not)
                server.shutdown(socket.SHUT_RDWR)
            while not ready.empty():
                ready.get().close()
