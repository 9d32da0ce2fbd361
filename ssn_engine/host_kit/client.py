"""The client of the engine worker (stdlib only): one request signature and one version handshake for every host.

:class:`Requests` numbers and frames requests, :func:`check_hello` is the
handshake (the worker must speak this kit's protocol) and :func:`reply_error`
turns a refused reply into :class:`EngineError`, without any I/O: the
blocking :class:`EngineClient` here (the GIMP filter, the soak test) and the
Krita docker's QProcess adapter both speak through them. A request is
``request(cmd, buffers, **params)``: the command, its named buffers and its
header parameters (docs/protocol.md).

:class:`EngineClient` spawns ``ssn-shadow serve`` (or connects to one on a
loopback port), checks its protocol with ``hello``, sends requests and
returns replies. A worker that is missing, crashes, hangs or speaks another
protocol raises :class:`WorkerUnavailable` with a message for the user; the
next request starts a fresh worker.

While a reply is awaited (a loopback worker's ``auth`` included) the client
asks its ``on_wait`` hook, about every :data:`WAIT_STEP` seconds, whether
the user has given up (a host shows its progress and handles its events
there): then the worker is stopped (a shared one it started, by its process
id) and :class:`Cancelled` raised, within one step (:func:`wait_for`).
"""

from __future__ import annotations

import collections
import itertools
import json
import os
import signal
import socket
import subprocess
import threading
import time
from collections.abc import Callable, Sequence
from pathlib import Path
from typing import IO, Any

from .engine_config import EngineConfig, worker_environment
from .protocol import PROTOCOL_VERSION, Buffer, ProtocolError, encode_header, read_message

__all__ = [
    "Cancelled",
    "EngineClient",
    "EngineError",
    "Requests",
    "WorkerUnavailable",
    "check_hello",
    "connect",
    "reply_error",
    "shared_client",
    "wait_for",
]


class EngineError(RuntimeError):
    """The worker answered with an error; ``kind`` is the protocol's error type."""

    def __init__(self, kind: str, message: str) -> None:
        super().__init__(message)
        self.kind = kind


class WorkerUnavailable(EngineError):
    """The worker could not be started, died or did not answer in time."""

    def __init__(self, message: str) -> None:
        super().__init__("WorkerUnavailable", message)


class Cancelled(EngineError):
    """The user stopped waiting for the worker, which was stopped; the next request starts a fresh one."""

    def __init__(self, cmd: str) -> None:
        super().__init__(
            "Cancelled", f"Cancelled while the shadow engine worked on '{cmd}'; it starts again with the next request."
        )


OnWait = Callable[[], bool]  # asked while a reply is awaited: True when the user has given up
WAIT_STEP = 0.05  # seconds between two questions to the on_wait hook


def wait_for(done: threading.Event, limit: float, on_wait: OnWait | None = None, step: float = WAIT_STEP) -> str:
    """Wait for ``done``, at most ``limit`` seconds, asking ``on_wait()`` about every ``step`` seconds whether to
    give up.

    Parameters
    ----------
    done
        Set when the awaited thing has happened.
    limit
        The deadline, in seconds from now.
    on_wait
        Called between steps (it may show progress or handle a host's events); True cancels the wait. None
        waits without asking.
    step
        Seconds between two calls of ``on_wait``.

    Returns
    -------
    str
        ``"done"``, ``"late"`` (``limit`` passed first) or ``"cancelled"``.
    """
    deadline = time.monotonic() + limit
    while True:
        left = deadline - time.monotonic()
        if done.wait(max(0.0, min(step, left)) if on_wait is not None else max(0.0, left)):
            return "done"
        if time.monotonic() >= deadline:
            return "late"
        if on_wait is not None and on_wait():
            return "cancelled"


def reply_error(reply: dict) -> EngineError | None:
    """The error a reply carries (None when it is ``ok``)."""
    if reply.get("ok"):
        return None
    error = reply.get("error") or {}
    return EngineError(error.get("type", "Internal"), error.get("message", "unknown engine error"))


def check_hello(reply: dict) -> dict:
    """The version handshake: ``hello``'s reply when the worker speaks this kit's :data:`PROTOCOL_VERSION`, else
    :class:`WorkerUnavailable` saying how to make them match."""
    if reply.get("protocol") != PROTOCOL_VERSION:
        raise WorkerUnavailable(
            f"the shadow engine speaks protocol {reply.get('protocol')!r}, this plug-in {PROTOCOL_VERSION}: "
            "re-run 'ssn-shadow install-plugin' from the engine's Python."
        )
    return reply


class Requests:
    """Request ids and framing for one worker connection (no I/O)."""

    def __init__(self) -> None:
        self._ids = itertools.count(1)

    def encode(
        self, cmd: str, buffers: dict[str, Buffer] | None = None, **params: Any
    ) -> tuple[int, list[bytes | memoryview]]:
        """A new request's id and the bytes to send, in order: its header line, then its buffers."""
        rid = next(self._ids)
        chunks: list[bytes | memoryview] = [encode_header({"id": rid, "cmd": cmd, **params}, buffers)]
        chunks.extend(memoryview(b.data).cast("B") for b in (buffers or {}).values())
        return rid, chunks


class EngineClient:
    """Talk to one worker: a spawned process (``command``) or a loopback ``address`` with the ``token`` that
    worker printed when it started (``listening HOST:PORT token=TOKEN``). ``on_wait`` is asked while a reply is
    awaited whether the user has given up (:func:`wait_for`); ``worker_pid``, the process of a loopback worker
    this user's plug-in started (:func:`shared_client`), is stopped with it when a wait is cancelled or late."""

    def __init__(
        self,
        command: Sequence[str] | None = None,
        address: tuple[str, int] | None = None,
        timeout: float = 120.0,
        token: str | None = None,
        env: dict[str, str] | None = None,
        on_wait: OnWait | None = None,
        worker_pid: int | None = None,
    ) -> None:
        if (command is None) == (address is None):
            raise ValueError("give exactly one of command or address")
        self.command, self.address, self.timeout, self.token = command, address, timeout, token
        self.env = env or {}
        self.on_wait, self.worker_pid = on_wait, worker_pid
        self._proc: subprocess.Popen[bytes] | None = None
        self._sock: socket.socket | None = None
        self._reader: IO[bytes] | None = None
        self._writer: IO[bytes] | None = None
        self._stderr: collections.deque[str] = collections.deque(maxlen=40)
        self._requests = Requests()
        self._lock = threading.Lock()
        self.info: dict[str, Any] = {}  # the hello reply of the worker this client talks to

    # -- connection --------------------------------------------------------
    @property
    def running(self) -> bool:
        if self._proc is not None:
            return self._proc.poll() is None
        return self._sock is not None

    def _start(self, limit: float) -> None:
        """Start the worker, or connect to a loopback one and authenticate, within ``limit`` seconds."""
        if self.command is not None:
            try:
                self._proc = subprocess.Popen(
                    list(self.command),
                    stdin=subprocess.PIPE,
                    stdout=subprocess.PIPE,
                    stderr=subprocess.PIPE,
                    env=worker_environment(os.environ, self.env),
                    creationflags=getattr(subprocess, "CREATE_NO_WINDOW", 0),  # no console flash on Windows
                )
            except OSError as exc:
                raise WorkerUnavailable(
                    f"could not start the shadow engine ({' '.join(self.command)}): {exc}. "
                    "Check the engine's Python in the plug-in's engine.json "
                    "(re-run 'ssn-shadow install-plugin')."
                ) from None
            self._reader, self._writer = self._proc.stdout, self._proc.stdin
            threading.Thread(target=self._drain, args=(self._proc.stderr,), daemon=True).start()
        else:
            self._connect(limit)

    def _connect(self, limit: float) -> None:
        """Connect to the loopback worker and send it its token (``auth``), the reply awaited as any other
        (:meth:`_await`: within ``limit`` seconds, ``on_wait`` asked meanwhile, the worker stopped if it is late or
        the user gives up). A worker frozen whole still has its port accept the connection (the kernel does), but
        nothing answers the ``auth``: a blocking read here sat out the socket's timeout (120 s)."""
        assert self.address is not None  # __init__: exactly one of command and address
        host, port = self.address
        try:  # loopback: accepted or refused at once (a frozen worker's kernel accepts for it)
            sock = socket.create_connection(self.address, timeout=max(0.1, min(limit, self.timeout)))
        except OSError as exc:
            raise WorkerUnavailable(f"no shadow engine is listening on {host}:{port}: {exc}") from None
        sock.settimeout(None)  # the waits are _await's, with their deadline and cancel check
        self._sock = sock
        self._reader, self._writer = sock.makefile("rb"), sock.makefile("wb")
        reply, _ = self._await("auth", [encode_header({"id": 0, "cmd": "auth", "token": self.token or ""})], limit)
        if not reply.get("ok"):
            self.close()
            raise WorkerUnavailable(
                f"the shadow engine on {host}:{port} refused this plug-in's token: give the token it printed "
                "when it started ('listening ... token=...') in engine.json, or restart it"
            )

    def _drain(self, stream: IO[bytes]) -> None:
        for line in iter(stream.readline, b""):
            self._stderr.append(line.decode("utf-8", "replace").rstrip())

    def close(self) -> None:
        """Stop the worker (or disconnect) without waiting for it. Safe from two threads at once (a request's
        thread that saw the worker die and a host thread that cancels): each works on what it took."""
        proc, sock = self._proc, self._sock
        self._proc = self._sock = self._reader = self._writer = None
        if proc is not None:
            try:
                proc.kill()
                proc.wait(timeout=5)
            except (OSError, subprocess.TimeoutExpired):
                pass
        if sock is not None:
            try:
                sock.shutdown(socket.SHUT_RDWR)  # wakes a thread blocked reading it (close alone may not)
                sock.close()
            except OSError:
                pass

    def _stop_worker(self) -> None:
        """Stop a worker that is working on a request nobody waits for any more, or is frozen: a spawned one by
        :meth:`close`, a loopback one this user started (``worker_pid``) by its process id too. Its port accepted
        this client's connection, which is still open, so that process is alive and listens where it was recorded
        (:func:`shared_client` names it only after checking its arguments where the system shows them)."""
        pid, self.worker_pid = self.worker_pid, None
        if pid is not None and self._sock is not None:
            try:
                os.kill(pid, getattr(signal, "SIGKILL", signal.SIGTERM))
            except OSError:
                pass
        self.close()

    def _died(self, what: str) -> WorkerUnavailable:
        tail = "\n".join(list(self._stderr)[-8:])
        self.close()
        detail = f"\nLast engine output:\n{tail}" if tail else ""
        return WorkerUnavailable(f"the shadow engine {what}; it will restart on the next request.{detail}")

    # -- requests ------------------------------------------------------------
    def request(
        self, cmd: str, buffers: dict[str, Buffer] | None = None, *, timeout: float | None = None, **params: Any
    ) -> tuple[dict, dict[str, Buffer]]:
        """Send one command with its ``buffers`` and header ``params``; return the reply header and buffers, or
        raise EngineError. A new worker is started (or connected to) first, and its protocol checked."""
        with self._lock:
            if self._proc is not None and self._proc.poll() is not None:
                # It died between requests (crash, OOM kill): say so once, with its last words,
                # instead of silently starting a fresh worker that has lost every cutout.
                raise self._died(f"stopped unexpectedly (exit status {self._proc.returncode})")
            if not self.running:
                self.close()
                self._start(self.timeout if timeout is None else timeout)
                hello, _ = self._exchange("hello", None, timeout, {})
                try:
                    self.info = check_hello(hello)
                except WorkerUnavailable:
                    self.close()
                    raise
            reply, reply_buffers = self._exchange(cmd, buffers, timeout, params)
            if cmd == "shutdown" and reply.get("ok"):
                self.close()  # it exits as asked: the next request starts a fresh one
        error = reply_error(reply)
        if error is not None:
            raise error
        return reply, reply_buffers

    def _exchange(
        self, cmd: str, buffers: dict[str, Buffer] | None, timeout: float | None, params: dict[str, Any]
    ) -> tuple[dict, dict[str, Buffer]]:
        """One request and its reply, within ``timeout`` (None: the client's), as :meth:`_await`."""
        _, chunks = self._requests.encode(cmd, buffers, **params)
        return self._await(cmd, chunks, self.timeout if timeout is None else timeout)

    def _await(self, cmd: str, chunks: list[bytes | memoryview], limit: float) -> tuple[dict, dict[str, Buffer]]:
        """Send ``chunks`` (request ``cmd``) and read its reply on a thread, waiting at most ``limit`` seconds and
        asking ``on_wait`` meanwhile (:func:`wait_for`); a worker that fails to answer, or whose answer the user
        stops waiting for, is stopped (WorkerUnavailable, Cancelled)."""
        reader, writer = self._reader, self._writer
        assert reader is not None and writer is not None  # connected by _start
        result: list = []
        done = threading.Event()

        def exchange() -> None:
            try:
                writer.writelines(chunks)
                writer.flush()
                result.append(read_message(reader))
            except (OSError, EOFError, ProtocolError, ValueError) as exc:
                result.append(exc)
            done.set()

        threading.Thread(target=exchange, daemon=True).start()
        try:
            outcome = wait_for(done, limit, self.on_wait)
        except BaseException:  # the hook failed: the reply would come to nobody
            self._stop_worker()
            raise
        if outcome == "cancelled":
            self._stop_worker()
            raise Cancelled(cmd)
        if outcome == "late":
            self._stop_worker()
            raise self._died(f"did not answer '{cmd}' within {limit:g} s")
        if isinstance(result[0], BaseException):
            raise self._died(f"stopped unexpectedly during '{cmd}' ({result[0]})")
        return result[0]


IDLE_TIMEOUT = 900.0  # seconds a shared worker waits for the next call before it exits
START_TIMEOUT = 120.0  # seconds a new shared worker may take to announce its port


def connect(
    config: EngineConfig, state_path: Path, timeout: float = 120.0, on_wait: OnWait | None = None
) -> EngineClient:
    """A client for an :class:`~engine_config.EngineConfig`: the worker at its address, the shared worker its
    command starts (recorded in ``state_path``, see :func:`shared_client`), or, without ``shared``, a worker of
    this client's own (started with the first request); ``on_wait`` as in :class:`EngineClient`."""
    if config.address is not None:
        return EngineClient(address=config.address, timeout=timeout, token=config.token, on_wait=on_wait)
    if config.shared:
        return shared_client(config.command, state_path, timeout, env=dict(config.env), on_wait=on_wait)
    return EngineClient(command=list(config.command), timeout=timeout, env=dict(config.env), on_wait=on_wait)


def shared_client(
    command: Sequence[str],
    state_path: Path,
    timeout: float = 120.0,
    idle_timeout: float = IDLE_TIMEOUT,
    env: dict[str, str] | None = None,
    on_wait: OnWait | None = None,
) -> EngineClient:
    """A client of a long-lived loopback worker started from ``command`` (``... ssn-shadow serve``): the one
    recorded in ``state_path`` while it answers, else a new one started detached with ``--port 0
    --idle-timeout`` and recorded there (readable by this user only). A plug-in that runs once per call (GIMP)
    then pays the engine's start-up on its first call only; the worker exits after ``idle_timeout`` idle
    seconds.

    The record names the worker's process and the process of the call that last took it (this one's). The client
    stops that worker (by its process id) when its user cancels a wait (``on_wait``) or a reply is late. A
    recorded worker that does not answer, its ``auth`` included (a worker frozen whole answers nothing), is busy
    with that call's request: it is left alone (and a new one started) after :data:`BUSY_TIMEOUT` while that
    call's process runs, and stopped after :data:`ORPHAN_TIMEOUT` when that process has gone (GIMP's own Cancel
    kills the plug-in while the worker works for it: the next call stops the worker that nobody waits for)."""
    state = _read_state(state_path, command)
    if state is not None and isinstance(state.get("pid"), int) and not _runs_worker(state["pid"], command):
        state = None  # the recorded worker has exited: its process id may be another program's now
    if state is not None:
        pid = state.get("pid") if isinstance(state.get("pid"), int) else None
        orphaned = pid is not None and not _process_runs(state.get("client"))
        reuse = EngineClient(
            address=(state["host"], state["port"]),
            timeout=timeout,
            token=state["token"],
            on_wait=on_wait,
            worker_pid=pid if orphaned else None,  # stopped if it does not answer in time
        )
        try:
            reuse.request("hello", timeout=ORPHAN_TIMEOUT if orphaned else BUSY_TIMEOUT)
        except Cancelled:
            raise
        except EngineError:
            reuse.close()
        else:
            reuse.worker_pid = pid
            _write_state(state_path, {**state, "client": os.getpid()})
            return reuse
    host, port, token, pid = _start_detached(command, idle_timeout, env or {})
    state = {"command": list(command), "host": host, "port": port, "token": token, "pid": pid, "client": os.getpid()}
    _write_state(state_path, state)
    return EngineClient(address=(host, port), timeout=timeout, token=token, on_wait=on_wait, worker_pid=pid)


BUSY_TIMEOUT = 10.0  # seconds a new call waits for a recorded worker that another running call may be using
ORPHAN_TIMEOUT = 2.0  # ... for one whose last call's process has gone, before it is stopped


def _process_runs(pid: Any) -> bool:
    """Whether process ``pid`` runs; True where that cannot be told (no POSIX signals, not a process id): a worker
    is only stopped where its last client is known to be gone."""
    if os.name != "posix" or not isinstance(pid, int) or isinstance(pid, bool) or pid <= 0:
        return True
    try:
        os.kill(pid, 0)
    except ProcessLookupError:
        return False
    except OSError:  # another user's process: it runs
        return True
    try:  # a zombie (killed, not yet reaped by its parent) runs no more; Linux's /proc tells
        with open(f"/proc/{pid}/stat", "rb") as f:
            return f.read().rpartition(b")")[2].split()[:1] != [b"Z"]
    except OSError:
        return True


def _runs_worker(pid: int, command: Sequence[str]) -> bool:
    """Whether process ``pid`` runs ``command`` as :func:`_start_detached` started it (its arguments end with
    ``command``'s, then ``--port 0 --idle-timeout S``), where the system shows a process's arguments (Linux's
    /proc); True elsewhere. A recorded worker that has exited may have left its process id to another program."""
    if not os.path.isdir("/proc/self"):
        return True
    try:
        with open(f"/proc/{pid}/cmdline", "rb") as f:
            argv = f.read().decode("utf-8", "surrogateescape").split("\0")[:-1]
    except OSError:
        return False  # no such process
    tail = [*command[1:], "--port", "0", "--idle-timeout"]  # command[0] may be a script run by its interpreter
    return len(argv) > len(tail) and argv[-len(tail) - 1 : -1] == tail


def _read_state(path: Path, command: Sequence[str]) -> dict | None:
    try:
        if os.name == "posix":
            info = path.stat()
            if info.st_uid != os.getuid() or info.st_mode & 0o077:  # another user's or readable by others
                return None
        state = json.loads(path.read_text(encoding="utf-8"))
    except (OSError, ValueError):
        return None
    ok = (
        isinstance(state, dict)
        and state.get("command") == list(command)
        and isinstance(state.get("port"), int)
        and isinstance(state.get("host"), str)
        and isinstance(state.get("token"), str)
    )
    return state if ok else None


def _write_state(path: Path, state: dict) -> None:
    try:
        fd = os.open(path, os.O_WRONLY | os.O_CREAT | os.O_TRUNC, 0o600)
        with os.fdopen(fd, "w", encoding="utf-8") as f:
            json.dump(state, f)
    except OSError:
        pass  # not recorded: the next call starts its own worker, nothing worse


def _start_detached(command: Sequence[str], idle_timeout: float, env: dict[str, str]) -> tuple[str, int, str, int]:
    """Start ``command --port 0 --idle-timeout S`` in its own session and read its ``listening`` line: its host,
    port, token and process id."""
    args = [*command, "--port", "0", "--idle-timeout", f"{idle_timeout:g}"]
    posix = os.name == "posix"  # POSIX: a new session; Windows: a detached process without a console
    flags = 0 if posix else getattr(subprocess, "DETACHED_PROCESS", 0) | getattr(subprocess, "CREATE_NO_WINDOW", 0)
    try:
        proc = subprocess.Popen(
            args,
            stdin=subprocess.DEVNULL,
            stdout=subprocess.PIPE,
            stderr=subprocess.DEVNULL,
            env=worker_environment(os.environ, env),
            start_new_session=posix,
            creationflags=flags,
        )
    except OSError as exc:
        raise WorkerUnavailable(f"could not start the shadow engine ({' '.join(args)}): {exc}") from None
    stdout = proc.stdout
    assert stdout is not None  # stdout=PIPE
    line: list[bytes] = []
    reader = threading.Thread(target=lambda: line.append(stdout.readline()), daemon=True)
    reader.start()
    reader.join(START_TIMEOUT)
    words = line[0].decode("utf-8", "replace").split() if line else []
    if len(words) != 3 or words[0] != "listening" or not words[2].startswith("token="):
        proc.kill()
        said = f"it said {line[0][:200]!r}" if line else f"it did not announce a port within {START_TIMEOUT:g} s"
        raise WorkerUnavailable(f"the shadow engine ({' '.join(args)}) did not start: {said}")
    stdout.close()  # the worker never writes to it again
    host, _, port = words[1].rpartition(":")
    return host, int(port), words[2].removeprefix("token="), proc.pid
