"""A worker frozen whole, for the GIMP filter's shared worker, without GIMP: the host kit's client
(ssn_engine.host_kit.client, which both plug-ins carry) gives it up within seconds, handshake included.

A worker stuck in a computation still authenticates new connections on a
thread of its own (tests/engine/test_client_cancel.py covers that one); a
worker frozen whole (its Python stuck holding its lock, a stopped process)
answers nothing, yet its port still accepts connections, the kernel doing it
for the process. The client sent ``auth`` and read its reply outside the
waits that have a deadline and a cancel check, under the socket's 120 s
timeout: the next GIMP call sat 122 to 124 s without progress or Cancel, and
the frozen worker stayed. tests/hung_worker.py ``--stop`` freezes whole (it
sends itself SIGSTOP).
"""

from __future__ import annotations

import contextlib
import json
import os
import signal
import socket
import subprocess
import sys
import time
from pathlib import Path

import pytest
from engine_helpers import HUNG_WORKER, CancelAfter, alive, gone_within, shared_render_call, wait_for_file

from ssn_engine.host_kit import client
from ssn_engine.host_kit.client import Cancelled, EngineClient, WorkerUnavailable
from ssn_engine.host_kit.engine_config import EngineConfig
from ssn_engine.host_kit.protocol import PROTOCOL_VERSION

pytestmark = pytest.mark.skipif(os.name != "posix" or not Path("/proc/self").is_dir(), reason="POSIX with /proc")


def whole_freezing_command(pid_file: Path) -> list[str]:
    return [sys.executable, str(HUNG_WORKER), str(PROTOCOL_VERSION), str(pid_file), "--stop"]


@pytest.fixture
def frozen_port():
    """A loopback port whose listener answers nothing (connections complete, as a frozen worker's do)."""
    with socket.create_server(("127.0.0.1", 0)) as server:
        yield server.getsockname()[1]


def test_a_frozen_workers_handshake_is_late_within_the_requests_limit(frozen_port):
    """Connecting to a worker frozen whole: the ``auth`` reply is awaited as any reply, within the request's
    limit (not the socket's timeout), with the host's hook asked meanwhile (its progress bar and Cancel)."""
    hook = CancelAfter()
    c = EngineClient(address=("127.0.0.1", frozen_port), timeout=15.0, token="t", on_wait=hook)
    start = time.monotonic()
    with pytest.raises(WorkerUnavailable, match="did not answer 'auth' within 1 s"):
        c.request("hello", timeout=1.0)
    took = time.monotonic() - start
    print(f"\nfrozen worker's handshake given up after {took:.2f} s")
    assert took < 3.0 and hook.calls >= 5, (took, hook.calls)
    assert not c.running


def test_the_user_can_give_up_during_the_handshake(frozen_port):
    hook = CancelAfter(0.3)
    c = EngineClient(address=("127.0.0.1", frozen_port), timeout=15.0, token="t", on_wait=hook)
    with pytest.raises(Cancelled, match="'auth'"):
        c.request("hello")
    assert hook.cancelled_at is not None and time.monotonic() - hook.cancelled_at < 0.5
    assert not c.running


def _freeze_a_shared_worker(tmp_path: Path) -> tuple[subprocess.Popen, list[str], Path, int]:
    """A call (a process of its own, as GIMP's plug-in is) whose shared worker froze whole on its render: (that
    process, still running, the worker's command, the record's path, the worker's process id)."""
    pid_file = tmp_path / "pid"
    command = whole_freezing_command(pid_file)
    state = tmp_path / "worker.json"
    plugin = shared_render_call(command, state)
    wait_for_file(Path(f"{pid_file}.frozen"))
    return plugin, command, state, int(pid_file.read_text())


def test_a_frozen_worker_whose_caller_was_killed_is_stopped_and_replaced_within_seconds(tmp_path):
    """GIMP's Cancel kills the plug-in while its shared worker is frozen whole. The next call's handshake with
    that worker is late after ORPHAN_TIMEOUT: the worker is killed and a fresh one started, in seconds (it used
    to take the socket's timeout, and leave the frozen worker behind)."""
    plugin, command, state, first = _freeze_a_shared_worker(tmp_path)
    plugin.kill()
    plugin.wait()
    hook = CancelAfter()
    start = time.monotonic()
    again = client.connect(EngineConfig(command=tuple(command), shared=True), state, timeout=15.0, on_wait=hook)
    try:
        reply, _ = again.request("hello")
        took = time.monotonic() - start
        print(f"\nthe call after a frozen worker had its fresh worker after {took:.2f} s")
        assert reply["protocol"] == PROTOCOL_VERSION and again.worker_pid != first
        assert took < 8.0, took
        assert hook.calls > 0  # the host's progress (and Cancel) while the frozen worker was tried
        assert gone_within(first, 2.0), "the frozen worker was left running"
        assert json.loads(state.read_text())["pid"] == again.worker_pid
    finally:
        again._stop_worker()
        with contextlib.suppress(OSError):
            os.kill(first, signal.SIGKILL)


def test_a_frozen_worker_another_running_call_took_is_left_alone(tmp_path, monkeypatch):
    """While the call that took the frozen worker still runs (it waits, with its own Cancel), a new call gives up
    on that worker after BUSY_TIMEOUT, without stopping it, and starts its own."""
    monkeypatch.setattr(client, "BUSY_TIMEOUT", 1.0)
    plugin, command, state, first = _freeze_a_shared_worker(tmp_path)
    other = None
    try:
        start = time.monotonic()
        other = client.connect(EngineConfig(command=tuple(command), shared=True), state, timeout=15.0)
        other.request("hello")
        assert time.monotonic() - start < 6.0
        assert other.worker_pid != first and alive(first)
    finally:
        if other is not None:
            other._stop_worker()
        plugin.kill()
        plugin.wait()
        with contextlib.suppress(OSError):
            os.kill(first, signal.SIGKILL)


def test_a_recorded_process_id_that_is_no_longer_the_worker_is_never_killed(tmp_path, frozen_port):
    """The recorded worker exited and its process id now names another program: that program is not killed, and
    a fresh worker is started at once (the silent port is not tried)."""
    pid_file = tmp_path / "pid"
    command = whole_freezing_command(pid_file)
    state = tmp_path / "worker.json"
    stranger = subprocess.Popen(["sleep", "60"])
    gone = subprocess.Popen(["true"])
    gone.wait()
    record = {"command": command, "host": "127.0.0.1", "port": frozen_port, "token": "t"}
    state.write_text(json.dumps({**record, "pid": stranger.pid, "client": gone.pid}))
    state.chmod(0o600)
    fresh = None
    try:
        start = time.monotonic()
        fresh = client.connect(EngineConfig(command=tuple(command), shared=True), state, timeout=15.0)
        fresh.request("hello")
        assert time.monotonic() - start < 5.0
        assert fresh.worker_pid == int(pid_file.read_text()) and alive(stranger.pid)
    finally:
        if fresh is not None:
            fresh._stop_worker()
        stranger.kill()
        stranger.wait()
