"""The host kit's engine set-up (what a packaged plug-in's Set up does), with real venv and pip: where it puts
things on each OS, which Python it takes, and each failure an artist can meet, said in words, resumable."""

import base64
import hashlib
import http.server
import json
import os
import shutil
import subprocess
import sys
import tempfile
import threading
import time
import zipfile
from pathlib import Path

import pytest

from ssn_engine.host_kit import engine_config, engine_setup, python_finder, setup_failures
from ssn_engine.host_kit.engine_setup import Bundle, EngineSetup, SetupJob
from ssn_engine.host_kit.python_finder import PythonFound
from ssn_engine.host_kit.setup_failures import SetupError

SYSTEM_PYTHON = [sys.executable]


def tiny_wheel(folder: Path, version: str) -> Path:
    """A wheel named like the engine's, holding an ``ssn_engine`` of that version and an ``onnxruntime`` module
    (what the set-up's check imports), no dependencies: the set-up's steps without the download."""
    name = f"ssn_shadow-{version}-py3-none-any.whl"
    dist = f"ssn_shadow-{version}.dist-info"
    files = {
        "ssn_engine/__init__.py": f"__version__ = {version!r}\n",
        "onnxruntime/__init__.py": "",
        f"{dist}/METADATA": f"Metadata-Version: 2.1\nName: ssn-shadow\nVersion: {version}\n",
        f"{dist}/WHEEL": "Wheel-Version: 1.0\nGenerator: test\nRoot-Is-Purelib: true\nTag: py3-none-any\n",
    }
    record = []
    for path, text in files.items():
        digest = base64.urlsafe_b64encode(hashlib.sha256(text.encode()).digest()).rstrip(b"=").decode()
        record.append(f"{path},sha256={digest},{len(text.encode())}")
    record.append(f"{dist}/RECORD,,")
    folder.mkdir(parents=True, exist_ok=True)
    with zipfile.ZipFile(folder / name, "w") as zf:
        for path, text in files.items():
            zf.writestr(path, text)
        zf.writestr(f"{dist}/RECORD", "\n".join(record) + "\n")
    return folder / name


def bundle_of(wheel: Path, version: str) -> Bundle:
    return Bundle(version, wheel, hashlib.sha256(wheel.read_bytes()).hexdigest())


def offline_env(index: str = "http://127.0.0.1:9/simple") -> dict[str, str]:
    """pip with no configuration of this machine's (mirrors, find-links), only ``index``, failing fast."""
    env = {k: v for k, v in os.environ.items() if not k.startswith("PIP_")}
    env.update(PIP_CONFIG_FILE=os.devnull, PIP_INDEX_URL=index, PIP_RETRIES="0", PIP_TIMEOUT="3")
    return env


def local_env() -> dict[str, str]:
    return dict(offline_env(), PIP_NO_INDEX="1")


# -- where and which ---------------------------------------------------------------------------------------------------
def test_data_folder_per_os():
    home = Path("/home/a")
    assert engine_setup.data_dir("linux", {}, home) == home / ".local/share/ssn-shadow"
    assert engine_setup.data_dir("linux", {"XDG_DATA_HOME": "/x"}, home) == Path("/x/ssn-shadow")
    assert engine_setup.data_dir("win32", {"LOCALAPPDATA": "C:/U/AppData/Local"}, home) == Path(
        "C:/U/AppData/Local/ssn-shadow"
    )
    assert engine_setup.data_dir("darwin", {}, home) == home / "Library/Application Support/ssn-shadow"
    assert engine_setup.data_dir("linux", {"SSN_SHADOW_DATA": "/d"}, home) == Path("/d")
    assert engine_setup.env_python(Path("/e"), "win32") == Path("/e/Scripts/python.exe")
    assert engine_setup.env_python(Path("/e"), "linux") == Path("/e/bin/python")


def test_candidates_put_the_hosts_own_python_first():
    paths = {"python3.12": "/usr/bin/python3.12", "python3": "/usr/bin/python3", "py": "C:/Windows/py.exe"}
    # Krita on Linux: its sys.executable is Debian's python3
    linux = python_finder.python_candidates("linux", "/usr/bin/python3", "/usr", (3, 11), paths.get)
    assert linux[0] == ["/usr/bin/python3"] and ["/usr/bin/python3.11"] in linux and ["/usr/bin/python3.12"] in linux
    # Krita on Windows: sys.executable is krita.exe; its embedded Python's folder is sys.base_prefix
    win = python_finder.python_candidates("win32", "C:/Krita/bin/krita.exe", "C:/Krita/python", (3, 10), paths.get)
    assert win[0] == [str(Path("C:/Krita/python/python.exe"))] and win[-1] == ["C:/Windows/py.exe", "-3"]
    assert ["C:/Krita/bin/krita.exe"] not in win
    mac = python_finder.python_candidates(
        "darwin", "", "/Applications/krita.app/Contents/Frameworks/Python", (3, 10), lambda name: None
    )
    assert mac[0] == [str(Path("/Applications/krita.app/Contents/Frameworks/Python/bin/python3.10"))]


def test_find_python_takes_a_recent_one_with_pip_and_says_what_to_install_otherwise():
    found = {
        "old": PythonFound("/usr/bin/python3.8", (3, 8, 10), True),
        "bare": PythonFound("/usr/bin/python3.11", (3, 11, 2), False),
        "full": PythonFound("/opt/python3.12", (3, 12, 1), True),
    }
    probe = lambda command: found.get(command[0])
    assert python_finder.find_python([["old"], ["bare"], ["full"]], probe).executable == "/opt/python3.12"
    assert python_finder.find_python([["old"], ["bare"]], probe).executable == "/usr/bin/python3.11"
    with pytest.raises(SetupError, match=r"needs Python 3.10 or newer; found only /usr/bin/python3.8 \(3.8.10\)"):
        python_finder.find_python([["old"], ["missing"]], probe)
    with pytest.raises(SetupError, match="No Python with its venv module was found. Install Python 3.10"):
        python_finder.find_python([["missing"]], probe)
    real = python_finder.probe_python(SYSTEM_PYTHON)
    assert real is not None and real.version[:2] == sys.version_info[:2]
    assert python_finder.probe_python(["/no/such/python"]) is None


def test_each_failure_is_said_in_words(tmp_path):
    env = {"PIP_INDEX_URL": "https://mirror.example/simple"}
    say = lambda out: setup_failures.explain_failure(out, tmp_path, env, "Installing the engine")
    assert "disk is full" in say("OSError: [Errno 28] No space left on device")
    assert f"Cannot write to {tmp_path}" in say("PermissionError: [Errno 13] Permission denied: '/x'")
    assert "proxy refused" in say("ProxyError('Cannot connect to proxy.')")
    assert "Cannot reach the package index (https://mirror.example/simple)" in say(
        "Failed to establish a new connection: [Errno 111] Connection refused"
    )
    other = say("Some other error\nValueError: bad wheel")
    assert other.startswith("Installing the engine failed (ValueError: bad wheel)") and "setup.log" in other


def test_the_progress_names_each_package_pip_starts_on():
    assert engine_setup.package_named("Collecting onnxruntime>=1.16") == "onnxruntime>=1.16"
    line = "Processing /opt/files/scikit_image-0.26.0-cp311-cp311-manylinux_2_24_x86_64.whl"
    assert engine_setup.package_named(line) == "scikit_image"
    line = "Requirement already satisfied: numpy>=1.24 in ./engine/lib/python3.11/site-packages (2.4.6)"
    assert engine_setup.package_named(line) == "numpy>=1.24"
    assert engine_setup.package_named("  Downloading onnxruntime-1.32.0-cp311.whl (27.8 MB)") == ""


# -- the set-up for real -----------------------------------------------------------------------------------------------
def test_set_up_then_ready_then_an_update_upgrades_in_place(tmp_path):
    wheel = tiny_wheel(tmp_path / "v1", "0.2.0")
    bundle = bundle_of(wheel, "0.2.0")
    data = tmp_path / "data"
    assert engine_setup.engine_state(bundle, data).status == "missing"
    steps = []
    python = EngineSetup(bundle, data, [SYSTEM_PYTHON], local_env()).run(lambda f, text: steps.append((f, text)))
    assert python == engine_setup.env_python(data / "engine") and python.exists()
    fractions = [f for f, _ in steps]
    assert fractions == sorted(fractions) and fractions[-1] == 1.0, steps
    assert steps[-1][1] == "The shadow engine 0.2.0 is set up."
    assert engine_setup.engine_state(bundle, data).status == "ready"
    # the plug-in updated: its new wheel asks for an update, which reuses the environment
    new = bundle_of(tiny_wheel(tmp_path / "v2", "0.3.0"), "0.3.0")
    state = engine_setup.engine_state(new, data)
    assert state.status == "outdated" and "(0.2.0 -> 0.3.0)" in state.describe(new)
    EngineSetup(new, data, [SYSTEM_PYTHON], local_env()).run(lambda f, text: None)
    assert engine_setup.engine_state(new, data).status == "ready"
    out = subprocess.run(
        [str(python), "-I", "-c", "import ssn_engine; print(ssn_engine.__version__)"], capture_output=True, text=True
    )
    assert out.stdout.strip() == "0.3.0"
    assert "reusing the environment" in (data / "setup.log").read_text()


def test_a_broken_environment_is_made_anew(tmp_path):
    bundle = bundle_of(tiny_wheel(tmp_path / "w", "0.2.0"), "0.2.0")
    data = tmp_path / "data"
    EngineSetup(bundle, data, [SYSTEM_PYTHON], local_env()).run(lambda f, text: None)
    python = engine_setup.env_python(data / "engine")
    python.unlink()
    python.write_text("#!/bin/sh\nexit 3\n")  # e.g. the Python it was made from was removed
    python.chmod(0o755)
    assert engine_setup.engine_state(bundle, data).status == "ready"  # the marker alone does not see it...
    EngineSetup(bundle, data, [SYSTEM_PYTHON], local_env()).run(lambda f, text: None)  # ...Set up repairs it
    assert "broken or of another Python: made anew" in (data / "setup.log").read_text()
    ok = subprocess.run([str(python), "-I", "-c", "import ssn_engine"], capture_output=True)
    assert ok.returncode == 0


def test_an_unreachable_index_says_so_and_leaves_no_engine(tmp_path):
    bundle = Bundle("0.2.0", requirement="ssn-shadow==0.2.0")
    data = tmp_path / "data"
    with pytest.raises(SetupError, match=r"Cannot reach the package index \(http://127.0.0.1:9/simple\)"):
        EngineSetup(bundle, data, [SYSTEM_PYTHON], offline_env()).run(lambda f, text: None)
    assert engine_setup.engine_state(bundle, data).status == "missing"
    assert "No matching distribution found" in (data / "setup.log").read_text()


def test_a_dead_proxy_is_named(tmp_path):
    """Behind a proxy that does not answer, the message names it (pip and the reachability check both use it)."""
    env = dict(offline_env("https://pypi.org/simple"), HTTPS_PROXY="http://127.0.0.1:9")
    with pytest.raises(SetupError, match=r"\(https://pypi.org/simple\) through the proxy http://127.0.0.1:9\. Check"):
        EngineSetup(Bundle("0.2.0", requirement="ssn-shadow==0.2.0"), tmp_path / "data", [SYSTEM_PYTHON], env).run(
            lambda f, text: None
        )


def test_an_index_without_the_package_says_what_is_missing(tmp_path):
    """A reachable index that lacks a package (another system's wheels only, say) is not a network problem."""

    class Empty(http.server.BaseHTTPRequestHandler):
        def do_GET(self):  # noqa: N802
            self.send_response(404)
            self.end_headers()

        def log_message(self, *args):
            pass

    server, index = _serve(Empty)
    try:
        with pytest.raises(SetupError, match=rf"The package index {index} has no ssn-shadow==0.2.0 for this Python"):
            EngineSetup(
                Bundle("0.2.0", requirement="ssn-shadow==0.2.0"), tmp_path / "data", [SYSTEM_PYTHON], offline_env(index)
            ).run(lambda f, text: None)
    finally:
        server.shutdown()


class _Stalling(http.server.BaseHTTPRequestHandler):
    """An index that accepts and never answers: a download that hangs until the artist cancels."""

    def do_GET(self):  # noqa: N802 (the standard library's API)
        time.sleep(30)

    def log_message(self, *args):
        pass


def _serve(handler) -> tuple[http.server.ThreadingHTTPServer, str]:
    server = http.server.ThreadingHTTPServer(("127.0.0.1", 0), handler)
    server.daemon_threads = True
    threading.Thread(target=server.serve_forever, daemon=True).start()
    return server, f"http://127.0.0.1:{server.server_address[1]}/simple"


def test_a_cancelled_install_is_killed_and_the_next_set_up_resumes(tmp_path):
    server, index = _serve(_Stalling)
    data = tmp_path / "data"
    try:
        env = dict(offline_env(index), PIP_TIMEOUT="60")
        job = SetupJob(EngineSetup(Bundle("0.2.0", requirement="ssn-shadow==0.2.0"), data, [SYSTEM_PYTHON], env))
        job.start()
        texts = []
        deadline = time.monotonic() + 60
        while not any("Installing the engine" in t for t in texts) and time.monotonic() < deadline:
            texts += [event.text for event in job.events()]
            time.sleep(0.05)
        time.sleep(1.0)  # pip is waiting on the index
        started = time.monotonic()
        job.cancel()
        job.wait(20)
        assert not job.running and time.monotonic() - started < 5  # pip was killed, not waited for
        (last,) = [e for e in job.events() if e.done]
        assert last.cancelled and "press Set up to resume" in last.error
    finally:
        server.shutdown()
    wheel = tiny_wheel(tmp_path / "w", "0.2.0")
    EngineSetup(bundle_of(wheel, "0.2.0"), data, [SYSTEM_PYTHON], local_env()).run(lambda f, text: None)
    log = (data / "setup.log").read_text()
    assert "cancelled" in log and "reusing the environment" in log and log.rstrip().endswith("done")


def _unprivileged():
    """Run a child as nobody when the tests run as root (who may write anywhere)."""
    if os.geteuid() != 0:
        return None
    return lambda: (os.setgid(65534), os.setuid(65534))


def test_a_read_only_folder_says_which_and_what_to_do(tmp_path):
    """The set-up of a plug-in whose data folder cannot be written: the message names the folder and the way out
    (run in a child Python as an unprivileged user, with the kit copied where that user can read it)."""
    public = Path(tempfile.mkdtemp(prefix="ssn-setup-ro-"))
    try:
        public.chmod(0o755)
        shutil.copytree(Path(engine_setup.__file__).parent, public / "host_kit")
        data = public / "data"
        data.mkdir()
        data.chmod(0o555)
        script = (
            "import sys, json; sys.path.insert(0, sys.argv[1]); from host_kit import engine_setup as s\n"
            "b = s.Bundle('0.2.0', requirement='ssn-shadow==0.2.0')\n"
            "try:\n    s.EngineSetup(b, s.Path(sys.argv[2]), [['/usr/bin/python3']]).run(lambda f, t: None)\n"
            "except s.SetupError as e:\n    print(json.dumps(str(e)))\n"
        )
        out = subprocess.run(
            ["/usr/bin/python3", "-c", script, str(public), str(data)],
            capture_output=True,
            text=True,
            preexec_fn=_unprivileged(),
            timeout=60,
        )
        message = json.loads(out.stdout)
        assert message.startswith(f"Cannot write to {data}. Make that folder writable"), message
        assert "SSN_SHADOW_DATA" in message
    finally:
        shutil.rmtree(public, ignore_errors=True)


def _pip_wheel() -> Path:
    """A pip wheel on this machine (Debian's python3-pip-whl, or CPython's ensurepip copy)."""
    import ensurepip

    places = [Path("/usr/share/python-wheels"), Path(ensurepip.__file__).parent / "_bundled"]
    found = sorted(p for place in places if place.is_dir() for p in place.glob("pip-*-py3-none-any.whl"))
    assert found, "no pip wheel on this machine"
    return found[-1]


def test_a_python_without_ensurepip_gets_pip_from_the_index(tmp_path):
    """Debian's python3 without python3-venv has no ensurepip: the environment is made without pip and pip's
    wheel comes from the index's simple page, checked against its sha256."""
    wheel = _pip_wheel()
    digest = hashlib.sha256(wheel.read_bytes()).hexdigest()
    page = f'<a href="../files/{wheel.name}#sha256={digest}">{wheel.name}</a>'.encode()

    class Index(http.server.BaseHTTPRequestHandler):
        def do_GET(self):  # noqa: N802
            body = page if self.path.endswith("/pip/") else wheel.read_bytes()
            self.send_response(200)
            self.send_header("Content-Length", str(len(body)))
            self.end_headers()
            self.wfile.write(body)

        def log_message(self, *args):
            pass

    server, index = _serve(Index)
    try:
        setup = EngineSetup(Bundle("0.2.0", requirement="x"), tmp_path / "data", [SYSTEM_PYTHON], offline_env(index))
        setup.data.mkdir()
        (setup.data / "cache").mkdir()
        setup._make_environment(PythonFound(sys.executable, sys.version_info[:3], ensurepip=False))
        assert subprocess.run([str(setup.python), "-m", "pip", "--version"], capture_output=True).returncode != 0
        setup._ensure_pip()
    finally:
        server.shutdown()
    out = subprocess.run([str(setup.python), "-m", "pip", "--version"], capture_output=True, text=True)
    assert out.returncode == 0 and out.stdout.startswith("pip "), out


# -- the plug-in finds it ---------------------------------------------------------------------------------------------
def test_a_packaged_plugin_asks_for_set_up_then_runs_the_environment(tmp_path, monkeypatch):
    for name in (engine_config.ADDRESS_ENV, engine_config.CONFIG_ENV):
        monkeypatch.delenv(name, raising=False)
    plugin = tmp_path / "plugin"
    wheel = tiny_wheel(plugin, "0.2.0")
    digest = hashlib.sha256(wheel.read_bytes()).hexdigest()
    (plugin / "setup.json").write_text(json.dumps({"version": "0.2.0", "wheel": wheel.name, "sha256": digest}))
    monkeypatch.setenv("SSN_SHADOW_DATA", str(tmp_path / "data"))
    with pytest.raises(engine_config.EngineSetupNeeded, match="not set up yet") as needed:
        engine_config.load_engine_config(plugin, "krita")
    assert needed.value.bundle.sha256 == digest
    EngineSetup(needed.value.bundle, tmp_path / "data", [SYSTEM_PYTHON], local_env()).run(lambda f, text: None)
    config = engine_config.load_engine_config(plugin, "krita")
    assert config.command == (str(engine_setup.env_python(tmp_path / "data" / "engine")), "-m", "ssn_engine", "serve")
    assert config.env == {"PYTHONPATH": ""}  # the host's Python paths never reach the engine's Python
    (plugin / "setup.json").write_text("{")
    with pytest.raises(engine_config.EngineConfigError, match="damaged.*import the plug-in's file again"):
        engine_config.load_engine_config(plugin, "krita")
