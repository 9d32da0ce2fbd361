import json
import sys
import zipfile
from pathlib import Path

import pytest

from plugin_krita.install import default_pykrita_dir, install


def test_default_folders():
    home = Path("/home/a")
    assert default_pykrita_dir("linux", {}, home) == home / ".local/share/krita/pykrita"
    assert default_pykrita_dir("linux", {"XDG_DATA_HOME": "/x"}, home) == Path("/x/krita/pykrita")
    assert default_pykrita_dir("win32", {"APPDATA": "C:/U/AppData/Roaming"}, home) == Path(
        "C:/U/AppData/Roaming/krita/pykrita"
    )
    assert default_pykrita_dir("darwin", {}, home) == home / "Library/Application Support/krita/pykrita"


@pytest.mark.parametrize("link", [False, True])
def test_install_copies_or_links(tmp_path, link):
    pkg = install(tmp_path, python="/opt/engine/bin/python", link=link)
    assert pkg == tmp_path / "ssn_shadow"
    assert (tmp_path / "ssn_shadow.desktop").exists()
    assert pkg.is_symlink() == link
    assert (pkg / "host_kit").is_symlink() == link  # a development install reads the engine's kit, never a stale copy
    for name in (
        "__init__.py",
        "host_kit/light_map.py",
        "host_kit/protocol.py",
        "host_kit/client.py",
        "host_kit/defaults.py",
    ):
        assert (pkg / name).is_file(), name
    config = json.loads((pkg / "engine.json").read_text())
    assert config["python"] == "/opt/engine/bin/python" and config["args"] == ["-m", "ssn_engine", "serve"]
    again = install(tmp_path, link=not link)  # re-install over either kind
    assert again.is_symlink() == (not link)
    assert json.loads((again / "engine.json").read_text())["python"] == sys.executable


def test_the_krita_benchmark_ships_its_driver(tmp_path):
    """``python -m plugin_krita.benchmark`` runs from an installed copy: the wheel holds the driver Krita runs."""
    import subprocess

    from plugin_krita import benchmark

    root = Path(__file__).resolve().parents[2]
    subprocess.run(
        [
            sys.executable,
            "-m",
            "pip",
            "wheel",
            "--no-deps",
            "--no-build-isolation",
            "-q",
            "-w",
            str(tmp_path),
            str(root),
        ],
        check=True,
        capture_output=True,
        timeout=300,
    )
    (wheel,) = tmp_path.glob("ssn_shadow-*.whl")
    names = zipfile.ZipFile(wheel).namelist()
    assert f"plugin_krita/{benchmark.DRIVER.name}" in names
    assert "plugin_krita/benchmark.py" in names
