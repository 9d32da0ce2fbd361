"""plugin_gimp.install: profile locations per OS, copy/link installs, engine.json variants."""

import json
import os
import sys
from pathlib import Path

import pytest

from plugin_gimp import install as inst
from ssn_engine.plugin_files import KIT_MODULES


@pytest.mark.parametrize(
    "platform, env, expected",
    [
        ("linux", {}, "/home/u/.config/GIMP/3.0/plug-ins/ssn-shadow"),
        ("linux", {"XDG_CONFIG_HOME": "/x"}, "/x/GIMP/3.0/plug-ins/ssn-shadow"),
        ("win32", {"APPDATA": "/C/Users/u/AppData/Roaming"}, "/C/Users/u/AppData/Roaming/GIMP/3.0/plug-ins/ssn-shadow"),
        ("win32", {}, "/home/u/AppData/Roaming/GIMP/3.0/plug-ins/ssn-shadow"),
        ("darwin", {}, "/home/u/Library/Application Support/GIMP/3.0/plug-ins/ssn-shadow"),
        ("linux", {"GIMP3_DIRECTORY": "/p"}, "/p/plug-ins/ssn-shadow"),
    ],
)
def test_default_dest(platform, env, expected):
    assert inst.default_dest(platform, env, Path("/home/u")) == Path(expected)


def test_copy_install(tmp_path):
    dest = inst.install(tmp_path / "plug-ins" / "ssn-shadow", python="/opt/venv/bin/python")
    main = dest / "ssn-shadow.py"
    assert main.is_file() and not main.is_symlink() and os.access(main, os.X_OK)
    for module in (
        "ssn_core.py",
        "ssn_settings.py",
        "ssn_pixels.py",
        "ssn_gimp_host.py",
        "ssn_dialog.py",
        "ssn_light_area.py",
        "ssn_preview.py",
        "ssn_engine_link.py",
    ):
        assert (dest / module).is_file(), module
    for module in KIT_MODULES:
        assert (dest / "host_kit" / module).is_file()
    config = json.loads((dest / "engine.json").read_text())
    assert config["python"] == "/opt/venv/bin/python" and config["args"] == ["-m", "ssn_engine", "serve"]


def test_default_python_is_this_one(tmp_path):
    dest = inst.install(tmp_path / "ssn-shadow")
    assert json.loads((dest / "engine.json").read_text())["python"] == sys.executable


def test_link_install_and_reinstall(tmp_path):
    dest = tmp_path / "ssn-shadow"
    inst.install(dest, link=True)
    assert (dest / "ssn-shadow.py").is_symlink()
    assert (dest / "ssn-shadow.py").resolve() == inst.SOURCE_DIR / "ssn-shadow.py"
    assert not (inst.SOURCE_DIR / "engine.json").exists()  # nothing written into the source tree
    (dest / "notes.txt").write_text("mine")
    (dest / "ssn_stale.py").write_text("")  # not ours: stays
    inst.install(dest)  # a copy over the link install
    assert not (dest / "ssn-shadow.py").is_symlink() and (dest / "notes.txt").read_text() == "mine"


def test_address_install(tmp_path):
    dest = inst.install(tmp_path / "ssn-shadow", address=("127.0.0.1", 4567), token="abc")
    config = json.loads((dest / "engine.json").read_text())
    assert config["address"] == ["127.0.0.1", 4567] and config["token"] == "abc" and "python" not in config


def test_installed_plugin_imports_shared_copies(tmp_path):
    """The installed modules find host_kit (not ssn_engine) when run from the plug-in folder."""
    import subprocess

    dest = inst.install(tmp_path / "ssn-shadow")
    code = (
        "import ssn_settings, ssn_preview, ssn_engine_link as l; print(l.light_map.__name__, l.light_editor.__name__)"
    )
    env = {k: v for k, v in os.environ.items() if k != "PYTHONPATH"}
    out = subprocess.run(
        [sys.executable, "-I", "-c", f"import sys; sys.path.insert(0, '.'); {code}"],
        cwd=dest,
        capture_output=True,
        text=True,
        env=env,
    )
    assert out.returncode == 0, out.stderr
    assert out.stdout.strip() == "host_kit.light_map host_kit.light_editor"
