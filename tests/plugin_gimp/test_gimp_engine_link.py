"""engine.json reading and the client it makes, without GIMP."""

import json

import pytest
import ssn_engine_link as link


def write(tmp_path, data):
    (tmp_path / "engine.json").write_text(data if isinstance(data, str) else json.dumps(data))
    return tmp_path


def test_command_config(tmp_path, monkeypatch):
    monkeypatch.delenv(link.ADDRESS_ENV, raising=False)
    config = {"python": "/opt/py/bin/python", "args": ["-m", "ssn_engine", "serve"]}
    cfg = link.load_engine_config(write(tmp_path, config))
    assert cfg == {"command": ["/opt/py/bin/python", "-m", "ssn_engine", "serve"], "shared": True}
    cfg = link.load_engine_config(write(tmp_path, {**config, "shared": False}))
    client = link.connect(cfg)
    assert client.command == cfg["command"] and not client.running  # its own worker, started lazily


def test_address_config_and_override(tmp_path, monkeypatch):
    monkeypatch.delenv(link.ADDRESS_ENV, raising=False)
    cfg = link.load_engine_config(write(tmp_path, {"address": ["127.0.0.1", 5123], "token": "s3cret"}))
    assert cfg == {"address": ["127.0.0.1", 5123], "token": "s3cret"}
    client = link.connect(cfg)
    assert client.address == ("127.0.0.1", 5123) and client.token == "s3cret"
    monkeypatch.setenv(link.ADDRESS_ENV, "t0k@localhost:7000")
    assert link.load_engine_config(tmp_path / "nowhere") == {"address": ["localhost", 7000], "token": "t0k"}


@pytest.mark.parametrize(
    "content, fragment",
    [
        (None, "install-plugin gimp"),
        ("{oops", "Cannot read"),
        ([1, 2], "JSON object"),
        ({"address": ["127.0.0.1"]}, '"address"'),
        ({"address": ["127.0.0.1", 5123], "token": 7}, '"token"'),
        ({"python": ""}, '"python"'),
        ({"python": "py", "args": "serve"}, '"args"'),
        ({"python": "py", "shared": "yes"}, '"shared"'),
    ],
)
def test_bad_configs_tell_what_to_do(tmp_path, monkeypatch, content, fragment):
    monkeypatch.delenv(link.ADDRESS_ENV, raising=False)
    if content is not None:
        write(tmp_path, content)
    with pytest.raises(link.EngineConfigError, match=fragment.replace("(", r"\(")):
        link.load_engine_config(tmp_path)


@pytest.mark.parametrize("text", ["nohost", ":80", "h:", "h:port", "h:70000"])
def test_bad_addresses(text):
    with pytest.raises(link.EngineConfigError):
        link.parse_address(text)


def test_unreachable_worker_is_a_clear_error():
    client = link.connect({"address": ["127.0.0.1", 1]}, timeout=2)
    with pytest.raises(link.client.WorkerUnavailable, match="no shadow engine is listening"):
        client.request("hello")


def test_the_shared_worker_outlives_a_call(tmp_path):
    """GIMP runs the plug-in once per filter call: the worker it starts serves the next call too (no second
    start-up), a dead one is replaced, and the record of it is this user's only (issue #14, item 15)."""
    import os
    import signal
    import sys

    command = [sys.executable, "-m", "ssn_engine", "serve"]
    cfg = {"command": command, "shared": True}
    first = link.connect(cfg, timeout=60, plugin_dir=tmp_path)
    pid = first.request("hello")[0]["pid"]
    first.close()  # the call ends
    state = tmp_path / link.WORKER_STATE
    assert state.stat().st_mode & 0o777 == 0o600
    second = link.connect(cfg, timeout=60, plugin_dir=tmp_path)
    assert second.request("hello")[0]["pid"] == pid  # the same worker: warm
    second.close()
    os.kill(pid, signal.SIGKILL)
    third = link.connect(cfg, timeout=60, plugin_dir=tmp_path)
    new_pid = third.request("hello")[0]["pid"]
    assert new_pid != pid
    third.request("shutdown")
    third.close()


def test_an_idle_worker_exits_by_itself():
    import subprocess
    import sys

    proc = subprocess.Popen(
        [sys.executable, "-m", "ssn_engine", "serve", "--port", "0", "--idle-timeout", "1", "--method", "geometric"],
        stdout=subprocess.PIPE,
        stderr=subprocess.PIPE,
        text=True,
    )
    try:
        assert proc.stdout.readline().startswith("listening 127.0.0.1:")
        assert proc.wait(timeout=60) == 0
        assert "no connection for 1 s" in proc.stderr.read()
    finally:
        if proc.poll() is None:
            proc.kill()
