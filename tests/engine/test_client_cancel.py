"""The kit's cancellable wait: a frozen worker is given up within a second when the user asks, and stopped.

The worker here is tests/hung_worker.py: it answers ``hello`` and
``set_cutout`` and never answers ``render``, as a worker stuck in a
computation would. No host is involved: the ``on_wait`` hook stands in for a
host's progress and Cancel button.
"""

from __future__ import annotations

import json
import sys
import threading
import time
from pathlib import Path

import pytest
from engine_helpers import HUNG_WORKER, CancelAfter, alive, gone_within, shared_render_call, wait_for_file

from ssn_engine.host_kit import client
from ssn_engine.host_kit.client import Cancelled, EngineClient, WorkerUnavailable, wait_for
from ssn_engine.host_kit.engine_config import EngineConfig
from ssn_engine.host_kit.protocol import PROTOCOL_VERSION


def hung_command(pid_file: Path) -> list[str]:
    return [sys.executable, str(HUNG_WORKER), str(PROTOCOL_VERSION), str(pid_file)]


def test_wait_for_says_done_late_or_cancelled():
    done = threading.Event()
    start = time.monotonic()
    assert wait_for(done, 0.3) == "late" and 0.29 < time.monotonic() - start < 1.0
    hook = CancelAfter(0.2)
    start = time.monotonic()
    assert wait_for(done, 30.0, hook) == "cancelled"
    assert time.monotonic() - start < 0.5 and hook.calls >= 3  # asked every step, given up at once
    threading.Timer(0.1, done.set).start()
    assert wait_for(done, 30.0, lambda: False) == "done"


def test_a_frozen_worker_is_cancelled_within_a_second_and_stopped(tmp_path):
    """A spawned worker frozen in 'render': the user gives up after 0.5 s, the client raises Cancelled within
    a second of that, the worker process is gone, and the next request starts a fresh one."""
    pid_file = tmp_path / "pid"
    hook = CancelAfter(0.5)
    c = EngineClient(command=hung_command(pid_file), timeout=120, on_wait=hook)
    try:
        key = c.request("set_cutout")[0]["cutout"]
        first = int(pid_file.read_text())
        with pytest.raises(Cancelled, match="Cancelled while the shadow engine worked on 'render'") as info:
            c.request("render", cutout=key)
        assert info.value.kind == "Cancelled"
        assert time.monotonic() - hook.cancelled_at < 1.0
        assert not c.running and gone_within(first, 1.0)
        hook.first, hook.delay = None, 1e9  # no more cancelling
        assert c.request("hello")[0]["protocol"] == PROTOCOL_VERSION
        assert int(pid_file.read_text()) != first  # a fresh worker
    finally:
        c.close()


def test_a_hook_that_fails_stops_the_worker(tmp_path):
    pid_file = tmp_path / "pid"

    def broken() -> bool:
        raise KeyboardInterrupt

    c = EngineClient(command=hung_command(pid_file), timeout=120)
    try:
        c.request("hello")
        c.on_wait = broken
        with pytest.raises(KeyboardInterrupt):
            c.request("render")
        assert not c.running and gone_within(int(pid_file.read_text()), 1.0)
    finally:
        c.close()


def test_a_late_reply_still_stops_the_worker(tmp_path):
    pid_file = tmp_path / "pid"
    c = EngineClient(command=hung_command(pid_file), timeout=0.5, on_wait=lambda: False)
    try:
        with pytest.raises(WorkerUnavailable, match="did not answer 'render' within 0.5 s"):
            c.request("render")
        assert gone_within(int(pid_file.read_text()), 1.0)
    finally:
        c.close()


def test_a_cancelled_shared_worker_is_stopped_and_replaced(tmp_path):
    """The shared loopback worker a plug-in starts (GIMP's default): cancelling a frozen render stops that
    process too (not only the connection, which would leave it frozen and its one slot taken), and the next call
    starts a fresh worker at once."""
    pid_file = tmp_path / "pid"
    config = EngineConfig(command=tuple(hung_command(pid_file)), shared=True)
    state = tmp_path / "worker.json"
    hook = CancelAfter(0.3)
    c = client.connect(config, state, timeout=120, on_wait=hook)
    first = int(pid_file.read_text())
    try:
        key = c.request("set_cutout")[0]["cutout"]
        with pytest.raises(Cancelled):
            c.request("render", cutout=key)
        assert time.monotonic() - hook.cancelled_at < 1.0
        assert gone_within(first, 1.0)
    finally:
        c.close()
    start = time.monotonic()
    again = client.connect(config, state, timeout=120)
    try:
        again.request("hello")
        assert int(pid_file.read_text()) != first and time.monotonic() - start < 5.0
    finally:
        again._stop_worker()


def test_a_busy_shared_worker_is_left_alone(tmp_path):
    """A recorded worker that does not answer a new call's hello (it may be serving another call) is not
    stopped: the new call starts a worker of its own."""
    pid_file = tmp_path / "pid"
    config = EngineConfig(command=tuple(hung_command(pid_file)), shared=True)
    state = tmp_path / "worker.json"
    busy = client.connect(config, state, timeout=120)
    first = int(pid_file.read_text())

    def render() -> None:
        try:
            busy.request("render")
        except WorkerUnavailable:
            pass  # its worker was stopped when the test ended

    threading.Thread(target=render, daemon=True).start()
    time.sleep(0.2)
    other = client.connect(config, state, timeout=120)
    try:
        other.request("hello")
        assert int(pid_file.read_text()) != first and alive(first)
    finally:
        other._stop_worker()
        busy._stop_worker()


def test_a_worker_whose_caller_was_killed_is_stopped_by_the_next_call(tmp_path):
    """GIMP's own Cancel (its progress bar's) kills the plug-in while the shared worker works for it: nobody
    waits for that worker any more. The next call stops it (its hello is not answered and the call that took it
    is gone) and starts a fresh one, in seconds, not the 10 s it grants a worker another running call uses."""
    pid_file = tmp_path / "pid"
    command = hung_command(pid_file)
    state = tmp_path / "worker.json"
    plugin = shared_render_call(command, state)
    try:
        frozen = Path(f"{pid_file}.frozen")
        wait_for_file(frozen)
        assert frozen.read_text() == "render"
        first = int(pid_file.read_text())
        assert json.loads(state.read_text())["client"] == plugin.pid
    finally:
        plugin.kill()  # as GIMP does
        plugin.wait()
    config = EngineConfig(command=tuple(command), shared=True)
    start = time.monotonic()
    again = client.connect(config, state, timeout=120)
    try:
        again.request("hello")
        assert time.monotonic() - start < client.BUSY_TIMEOUT
        assert int(pid_file.read_text()) != first and gone_within(first, 1.0)
    finally:
        again._stop_worker()
