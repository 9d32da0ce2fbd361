"""The host kit's engine client as a QProcess: asynchronous, for Krita's event loop (docs/protocol.md).

Requests are numbered, framed and checked by the kit's client
(:class:`~ssn_engine.host_kit.client.Requests`, the ``hello`` handshake of
:func:`~ssn_engine.host_kit.client.check_hello`,
:func:`~ssn_engine.host_kit.client.reply_error`), with the kit's request
signature; this adapter only moves the bytes. Requests are written at once
and answered in order; each reply calls its callback from the Qt event loop,
so the UI never waits. A worker that cannot start, exits, speaks another
protocol or misses a deadline fails every pending request with a message for
people, and the next request starts a fresh worker.
"""

from __future__ import annotations

import collections
import time
from collections.abc import Callable
from dataclasses import dataclass
from typing import Any

from pathlib import Path

from PyQt5.QtCore import QObject, QProcess, QProcessEnvironment, QTimer, pyqtSignal

from .shared import client, engine_config, protocol

EngineConfig = engine_config.EngineConfig
EngineError = client.EngineError  # the worker answered with an error (``kind`` from the protocol) or is unavailable
OnReply = Callable[[dict, dict], None]
OnError = Callable[[EngineError], None]


PLUGIN_DIR = Path(__file__).resolve().parent


def engine_command(plugin_dir: Path = PLUGIN_DIR) -> EngineConfig:
    """The command that starts this docker's worker (:func:`engine_config.load_engine_config`)."""
    config = engine_config.load_engine_config(plugin_dir, "krita")
    if config.address is not None:
        raise engine_config.EngineConfigError(
            f"{config.source} names a running worker ({config.describe()}); the Krita plug-in starts its own. "
            "Re-run 'ssn-shadow install-plugin krita' from the engine's Python."
        )
    return config


@dataclass
class _Pending:
    id: int
    cmd: str
    deadline: float
    timeout_s: float
    on_reply: OnReply | None
    on_error: OnError | None


class EngineProcess(QObject):
    """One worker process and its queue of pending requests."""

    ready = pyqtSignal(dict)  # the 'hello' reply after each start
    stateChanged = pyqtSignal(str)  # "starting", "ready", "stopped"

    def __init__(
        self,
        command: Callable[[], EngineConfig] = engine_command,
        timeout_s: float = 120.0,
        parent: QObject | None = None,
    ) -> None:
        super().__init__(parent)
        self._command_provider, self.timeout_s = command, timeout_s
        self._proc: QProcess | None = None
        self._decoder = protocol.MessageDecoder()
        self._pending: collections.OrderedDict[int, _Pending] = collections.OrderedDict()
        self._stderr: collections.deque[str] = collections.deque(maxlen=40)
        self._requests = client.Requests()
        self._command: EngineConfig | None = None
        self.info: dict[str, Any] = {}
        self._watchdog = QTimer(self)
        self._watchdog.setInterval(250)
        self._watchdog.timeout.connect(self._check_deadlines)

    # -- process -------------------------------------------------------------
    @property
    def running(self) -> bool:
        return self._proc is not None and self._proc.state() != QProcess.ProcessState.NotRunning

    def _start(self) -> None:
        self._command = self._command_provider()
        proc = QProcess(self)
        env = QProcessEnvironment()
        base = QProcessEnvironment.systemEnvironment()
        environment = engine_config.worker_environment({k: base.value(k) for k in base.keys()}, self._command.env)
        for key, value in environment.items():
            env.insert(key, value)
        proc.setProcessEnvironment(env)
        proc.readyReadStandardOutput.connect(self._on_stdout)
        proc.readyReadStandardError.connect(self._on_stderr)
        proc.errorOccurred.connect(self._on_process_error)
        proc.finished.connect(self._on_finished)
        self._proc, self._decoder = proc, protocol.MessageDecoder()
        self._stderr.clear()
        self.info = {}
        self.stateChanged.emit("starting")
        proc.start(self._command.command[0], list(self._command.command[1:]))
        self._watchdog.start()
        self._send("hello", None, self._on_hello, None, self.timeout_s, {})

    def _on_hello(self, reply: dict, buffers: dict) -> None:
        try:
            self.info = client.check_hello(reply)
        except EngineError as exc:
            self._fail_all(str(exc))
            self.stop()
            return
        self.stateChanged.emit("ready")
        self.ready.emit(reply)

    def stop(self) -> None:
        """Kill the worker (pending requests fail) without waiting."""
        proc, self._proc = self._proc, None
        if proc is not None:
            for sig in (proc.readyReadStandardOutput, proc.readyReadStandardError, proc.errorOccurred, proc.finished):
                try:
                    sig.disconnect()
                except TypeError:
                    pass
            if proc.state() != QProcess.ProcessState.NotRunning:
                proc.kill()
                proc.waitForFinished(2000)
            proc.deleteLater()
        self._watchdog.stop()
        self.stateChanged.emit("stopped")

    def cancel(self) -> None:
        """Give up on every pending request (their callbacks are dropped) and stop the worker; the next request
        starts a fresh one."""
        self._pending.clear()
        self.stop()

    def shutdown(self) -> None:
        """Ask the worker to exit, then stop it."""
        proc = self._proc
        if proc is not None and proc.state() != QProcess.ProcessState.NotRunning:
            self._send("shutdown", None, None, None, 5.0, {})
            proc.waitForFinished(3000)
        self.stop()

    # -- requests ------------------------------------------------------------
    def request(
        self,
        cmd: str,
        buffers: dict[str, protocol.Buffer] | None = None,
        *,
        on_reply: OnReply | None = None,
        on_error: OnError | None = None,
        timeout: float | None = None,
        **params: Any,
    ) -> int:
        """Send one command with its ``buffers`` and header ``params`` (the kit's request signature);
        ``on_reply(header, buffers)`` or ``on_error(EngineError)`` follows. Returns the request's id."""
        if not self.running:
            self.stop()
            try:
                self._start()
            except engine_config.EngineConfigError as exc:
                self._deliver_error(on_error, client.WorkerUnavailable(str(exc)))
                return -1
        return self._send(cmd, buffers, on_reply, on_error, timeout or self.timeout_s, params)

    def _send(
        self,
        cmd: str,
        buffers: dict[str, protocol.Buffer] | None,
        on_reply: OnReply | None,
        on_error: OnError | None,
        timeout_s: float,
        params: dict[str, Any],
    ) -> int:
        proc = self._proc
        assert proc is not None, "_send follows _start"
        rid, chunks = self._requests.encode(cmd, buffers, **params)
        self._pending[rid] = _Pending(rid, cmd, time.monotonic() + timeout_s, timeout_s, on_reply, on_error)
        for chunk in chunks:
            proc.write(bytes(chunk))
        return rid

    # -- replies ---------------------------------------------------------------
    def _on_stdout(self) -> None:
        if self._proc is None:
            return
        try:
            messages = self._decoder.feed(bytes(self._proc.readAllStandardOutput()))
        except protocol.ProtocolError as exc:
            self._died(f"sent a malformed reply ({exc})")
            return
        for message in messages:
            self._dispatch(*message)

    def _dispatch(self, header: dict, buffers: dict) -> None:
        rid = header.get("id")
        pending = self._pending.pop(rid, None) if isinstance(rid, int) else None
        if pending is None:
            return
        error = client.reply_error(header)
        if error is None:
            if pending.on_reply is not None:
                pending.on_reply(header, buffers)
        else:
            self._deliver_error(pending.on_error, error)

    @staticmethod
    def _deliver_error(on_error: OnError | None, error: EngineError) -> None:
        if on_error is not None:
            on_error(error)

    # -- failures --------------------------------------------------------------
    def _on_stderr(self) -> None:
        if self._proc is not None:
            text = bytes(self._proc.readAllStandardError()).decode("utf-8", "replace")
            self._stderr.extend(line for line in text.splitlines() if line.strip())

    def _on_process_error(self, error: QProcess.ProcessError) -> None:
        if error == QProcess.ProcessError.FailedToStart:
            cmd = self._command.describe() if self._command else "?"
            self._fail_all(
                f"could not start the shadow engine ({cmd}). Check the Python named in the plug-in's "
                "engine.json (re-run 'ssn-shadow install-plugin krita' from the engine's environment)."
            )
            self.stop()

    def _on_finished(self, code: int, status: QProcess.ExitStatus) -> None:
        self._on_stderr()
        how = "crashed" if status == QProcess.ExitStatus.CrashExit else f"exited with code {code}"
        self._died(how)

    def _died(self, what: str) -> None:
        tail = "\n".join(list(self._stderr)[-8:])
        detail = f"\nLast engine output:\n{tail}" if tail else ""
        self.stop()
        self._fail_all(f"the shadow engine {what}; it will restart on the next request.{detail}")

    def _check_deadlines(self) -> None:
        now = time.monotonic()
        late = next((p for p in self._pending.values() if p.deadline < now), None)
        if late is not None:
            self._died(f"did not answer '{late.cmd}' within {late.timeout_s:g} s and was stopped")

    def _fail_all(self, message: str) -> None:
        pending, self._pending = list(self._pending.values()), collections.OrderedDict()
        for p in pending:
            self._deliver_error(p.on_error, client.WorkerUnavailable(message))
