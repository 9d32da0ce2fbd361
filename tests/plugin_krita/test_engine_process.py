import sys

import pytest

from krita_helpers import cutout_alpha, wait_until, worker_command
from plugin_krita.ssn_shadow.engine import EngineProcess
from ssn_engine.host_kit.engine_config import EngineConfig
from plugin_krita.ssn_shadow.shared import protocol


class Calls:
    def __init__(self):
        self.replies, self.errors = [], []

    def ok(self, header, buffers):
        self.replies.append((header, buffers))

    def err(self, error):
        self.errors.append(error)

    @property
    def done(self):
        return bool(self.replies or self.errors)


def test_real_worker_round_trip(qapp):
    engine = EngineProcess(worker_command)
    try:
        calls = Calls()
        alpha = protocol.Buffer("uint8", (160, 200), cutout_alpha())
        engine.request("set_cutout", {"alpha": alpha}, on_reply=calls.ok, on_error=calls.err)
        assert wait_until(lambda: calls.done), "no reply"
        assert not calls.errors, calls.errors
        cutout = calls.replies[0][0]["cutout"]
        assert engine.info["protocol"] == protocol.PROTOCOL_VERSION and engine.info["resolution"] > 0
        render = Calls()
        params = {"cutout": cutout, "preset": "softbox", "format": {"dtype": "uint8", "channels": "bgra"}}
        engine.request("render", on_reply=render.ok, on_error=render.err, **params)
        assert wait_until(lambda: render.done)
        header, buffers = render.replies[0]
        assert header["width"] > 0 and buffers["layer"].shape == (header["height"], header["width"], 4)
        bad = Calls()
        engine.request("render", cutout="nope", preset="softbox", on_reply=bad.ok, on_error=bad.err)
        assert wait_until(lambda: bad.done)
        assert bad.errors[0].kind == "UnknownCutout" and engine.running  # an error does not end the worker
    finally:
        engine.shutdown()


def test_missing_worker_gives_a_message_then_restarts(qapp):
    commands = [EngineConfig(("/nonexistent/python", "-m", "ssn_engine", "serve")), worker_command()]
    engine = EngineProcess(lambda: commands.pop(0) if len(commands) > 1 else commands[0])
    try:
        calls = Calls()
        engine.request("hello", on_reply=calls.ok, on_error=calls.err)
        assert wait_until(lambda: calls.done)
        assert calls.errors and "could not start the shadow engine" in str(calls.errors[0])
        again = Calls()
        engine.request("hello", on_reply=again.ok, on_error=again.err)
        assert wait_until(lambda: again.done) and again.replies, again.errors
    finally:
        engine.shutdown()


def test_crashing_worker(qapp):
    engine = EngineProcess(lambda: worker_command("-c", "import sys; print('boom', file=sys.stderr); sys.exit(3)"))
    calls = Calls()
    engine.request("hello", on_reply=calls.ok, on_error=calls.err)
    assert wait_until(lambda: calls.done)
    message = str(calls.errors[0])
    assert "exited with code 3" in message and "restart on the next request" in message and "boom" in message
    engine.stop()


def test_hanging_worker_is_stopped(qapp):
    engine = EngineProcess(lambda: worker_command("-c", "import time; time.sleep(60)"), timeout_s=1.0)
    calls = Calls()
    engine.request("hello", on_reply=calls.ok, on_error=calls.err)
    assert wait_until(lambda: calls.done, 15)
    assert "did not answer 'hello' within 1 s" in str(calls.errors[0])
    assert not engine.running
    engine.stop()


@pytest.mark.skipif(sys.platform == "win32", reason="POSIX shell")
def test_garbage_output_is_a_clear_error(qapp):
    script = "import sys, time; sys.stdout.write('{not json\\n'); sys.stdout.flush(); time.sleep(5)"
    engine = EngineProcess(lambda: worker_command("-c", script))
    calls = Calls()
    engine.request("hello", on_reply=calls.ok, on_error=calls.err)
    assert wait_until(lambda: calls.done, 15)
    assert "malformed reply" in str(calls.errors[0])
    engine.stop()
