"""engine.json reading (the host kit's one reader, used by both plug-ins) and the clients it makes."""

import json

import pytest

from ssn_engine.host_kit import client
from ssn_engine.host_kit.engine_config import (
    ADDRESS_ENV,
    CONFIG_ENV,
    EngineConfig,
    EngineConfigError,
    load_engine_config,
    parse_address,
    worker_environment,
)


@pytest.fixture(autouse=True)
def no_overrides(monkeypatch):
    monkeypatch.delenv(ADDRESS_ENV, raising=False)
    monkeypatch.delenv(CONFIG_ENV, raising=False)


def write(tmp_path, data):
    (tmp_path / "engine.json").write_text(data if isinstance(data, str) else json.dumps(data))
    return tmp_path


def test_command_config(tmp_path):
    config = {"python": "/opt/py/bin/python", "args": ["-m", "ssn_engine", "serve"]}
    cfg = load_engine_config(write(tmp_path, config), "gimp")
    assert (cfg.command, cfg.shared, cfg.address) == (("/opt/py/bin/python", "-m", "ssn_engine", "serve"), True, None)
    cfg = load_engine_config(write(tmp_path, {**config, "shared": False, "env": {"OMP_NUM_THREADS": "2"}}), "krita")
    own = client.connect(cfg, tmp_path / "worker.json")
    assert own.command == list(cfg.command) and not own.running  # its own worker, started lazily
    assert own.env == {"OMP_NUM_THREADS": "2"}


def test_address_config_and_overrides(tmp_path, monkeypatch):
    cfg = load_engine_config(write(tmp_path, {"address": ["127.0.0.1", 5123], "token": "s3cret"}), "gimp")
    assert (cfg.address, cfg.token) == (("127.0.0.1", 5123), "s3cret")
    remote = client.connect(cfg, tmp_path / "worker.json")
    assert remote.address == ("127.0.0.1", 5123) and remote.token == "s3cret"
    other = tmp_path / "elsewhere.json"
    other.write_text(json.dumps({"python": "/usr/bin/python3"}))
    monkeypatch.setenv(CONFIG_ENV, str(other))
    assert load_engine_config(tmp_path, "krita").command == ("/usr/bin/python3", "-m", "ssn_engine", "serve")
    monkeypatch.setenv(ADDRESS_ENV, "t0k@localhost:7000")
    cfg = load_engine_config(tmp_path / "nowhere", "gimp")
    assert (cfg.address, cfg.token) == (("localhost", 7000), "t0k")


def test_ssn_shadow_on_path_when_nothing_is_configured(tmp_path, monkeypatch):
    exe = tmp_path / "bin" / "ssn-shadow"
    exe.parent.mkdir()
    exe.write_text("#!/bin/sh\n")
    exe.chmod(0o755)
    monkeypatch.setenv("PATH", str(exe.parent))
    assert load_engine_config(tmp_path, "krita") == EngineConfig(command=(str(exe), "serve"), source="PATH")


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
        ({"python": "py", "env": {"A": 1}}, '"env"'),
        ({"python": "py", "shared": "yes"}, '"shared"'),
    ],
)
def test_bad_configs_tell_what_to_do(tmp_path, monkeypatch, content, fragment):
    monkeypatch.setenv("PATH", str(tmp_path / "empty"))  # no ssn-shadow to fall back on
    if content is not None:
        write(tmp_path, content)
    with pytest.raises(EngineConfigError, match=fragment.replace("(", r"\(")):
        load_engine_config(tmp_path, "gimp")


@pytest.mark.parametrize("text", ["nohost", ":80", "h:", "h:port", "h:70000"])
def test_bad_addresses(text):
    with pytest.raises(EngineConfigError):
        parse_address(text)


def test_worker_environment_drops_the_hosts_python():
    env = worker_environment({"PATH": "/bin", "PYTHONHOME": "/krita/python"}, {"PYTHONPATH": "/repo"})
    assert env == {"PATH": "/bin", "PYTHONPATH": "/repo", "PYTHONUNBUFFERED": "1"}


def test_unreachable_worker_is_a_clear_error(tmp_path):
    client_ = client.connect(EngineConfig(address=("127.0.0.1", 1)), tmp_path / "worker.json", timeout=2)
    with pytest.raises(client.WorkerUnavailable, match="no shadow engine is listening"):
        client_.request("hello")


def test_the_shared_worker_outlives_a_call(tmp_path):
    """GIMP runs the plug-in once per filter call: the worker it starts serves the next call too (no second
    start-up), a dead one is replaced, and the record of it is this user's only (issue #14, item 15)."""
    import os
    import signal
    import sys

    command = [sys.executable, "-m", "ssn_engine", "serve"]
    cfg = EngineConfig(command=tuple(command), shared=True)
    state = tmp_path / "worker.json"
    first = client.connect(cfg, state, timeout=60)
    pid = first.request("hello")[0]["pid"]
    first.close()  # the call ends
    assert state.stat().st_mode & 0o777 == 0o600
    second = client.connect(cfg, state, timeout=60)
    assert second.request("hello")[0]["pid"] == pid  # the same worker: warm
    second.close()
    os.kill(pid, signal.SIGKILL)
    third = client.connect(cfg, state, timeout=60)
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
