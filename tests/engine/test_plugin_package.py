"""``ssn-shadow package krita|gimp``: one reproducible file per host, carrying the plug-in, the host kit with its
Set up, and the engine (its wheel, model inside, or the exact requirement)."""

import hashlib
import json
import stat
import zipfile

from plugin_gimp import install as gimp_install
from plugin_krita import install as krita_install
from ssn_engine import __version__
from ssn_engine.cli import main
from ssn_engine.plugin_package import package

WHEEL = f"ssn_shadow-{__version__}-py3-none-any.whl"


def test_the_krita_package_is_reproducible_and_carries_the_engine(tmp_path):
    first = package(krita_install, tmp_path / "a.zip")
    second = package(krita_install, tmp_path / "b.zip")  # the wheel built again from the same sources
    assert first.read_bytes() == second.read_bytes()
    archive = zipfile.ZipFile(first)
    names = archive.namelist()
    assert "ssn_shadow.desktop" in names and "ssn_shadow/" in names  # what Krita's importer looks for
    assert "ssn_shadow/host_kit/engine_setup.py" in names and "ssn_shadow/engine.json" not in names
    setup = json.loads(archive.read("ssn_shadow/setup.json"))
    wheel = archive.read(f"ssn_shadow/{WHEEL}")
    assert setup == {"version": __version__, "wheel": WHEEL, "sha256": hashlib.sha256(wheel).hexdigest()}
    (tmp_path / WHEEL).write_bytes(wheel)
    inside = zipfile.ZipFile(tmp_path / WHEEL).namelist()
    assert "ssn_engine/models/model.json" in inside and any(n.endswith(".onnx") for n in inside)
    # built from the sources only: nothing a development install generated in the plug-in folders
    assert not any("/host_kit/" in n and n.startswith("plugin_") for n in inside)
    assert not any("__pycache__" in n for n in names + inside)


def test_the_gimp_package_unpacks_into_the_plugins_folder(tmp_path):
    out = package(gimp_install, tmp_path / "g.zip", requirement=f"ssn-shadow=={__version__}")
    archive = zipfile.ZipFile(out)
    names = archive.namelist()
    assert all(n.startswith("ssn-shadow/") for n in names)
    script = archive.getinfo("ssn-shadow/ssn-shadow.py")
    assert stat.S_IMODE(script.external_attr >> 16) == 0o755  # GIMP runs only an executable plug-in
    assert stat.S_IMODE(archive.getinfo("ssn-shadow/ssn_core.py").external_attr >> 16) == 0o644
    assert json.loads(archive.read("ssn-shadow/setup.json")) == {
        "version": __version__,
        "requirement": f"ssn-shadow=={__version__}",
    }
    assert not any(n.endswith(".whl") or n.endswith("engine.json") for n in names)
    archive.extractall(tmp_path / "plug-ins")
    assert (tmp_path / "plug-ins" / "ssn-shadow" / "host_kit" / "engine_setup.py").is_file()


def test_the_package_command_refuses_what_it_cannot_build(tmp_path, capsys):
    assert main(["package", "gimp", "--out", str(tmp_path / "g.zip"), "--wheel", str(tmp_path / "none.whl")]) == 1
    assert "no such wheel" in capsys.readouterr().err
    both = ["package", "krita", "--out", str(tmp_path / "k.zip"), "--wheel", "w.whl", "--requirement", "r"]
    assert main(both) == 2
    assert "not both" in capsys.readouterr().err
    assert not list(tmp_path.iterdir())  # nothing written
