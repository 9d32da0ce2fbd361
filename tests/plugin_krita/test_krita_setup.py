"""The one-file Krita package in real Krita: imported as Krita's importer does into a fresh profile with no engine
anywhere, its docker sets the engine up (cancelled once, then resumed) and makes a shadow."""

import sys
import zipfile
from pathlib import Path

import pytest
from krita_helpers import run_kritarunner

from plugin_krita import install as krita_install
from ssn_engine import __version__
from ssn_engine.plugin_package import package

pytestmark = pytest.mark.krita
IMPORTER = Path("/usr/share/krita/pykrita/plugin_importer")


def import_like_krita(archive: Path, resources: Path) -> Path:
    """Krita's own importer (Tools > Scripts > Import Python Plugin from File) on ``archive``; the pykrita folder."""
    if not IMPORTER.is_dir():
        pytest.skip("Krita's plug-in importer is not installed")
    sys.path.insert(0, str(IMPORTER))
    try:
        import plugin_importer
    finally:
        sys.path.remove(str(IMPORTER))
    resources.mkdir(parents=True)
    imported = plugin_importer.PluginImporter(str(archive), str(resources), lambda plugin: True).import_all()
    assert [p["name"] for p in imported] == ["ssn_shadow"]
    return resources / "pykrita"


def test_the_krita_package_sets_up_its_engine_and_makes_a_shadow(tmp_path):
    archive = package(krita_install, tmp_path / "ssn-shadow-krita.zip")
    pykrita = import_like_krita(archive, tmp_path / "krita-resources")
    assert (pykrita / "ssn_shadow" / f"ssn_shadow-{__version__}-py3-none-any.whl").is_file()
    assert not (pykrita / "ssn_shadow" / "engine.json").exists()
    home = tmp_path / "home"
    (home / ".config").mkdir(parents=True)
    (home / ".config" / "kritadisplayrc").write_text("[General]\nOpenGLRenderer=none\n")
    env = {"HOME": str(home), "XDG_CONFIG_HOME": str(home / ".config"), "XDG_DATA_HOME": str(home / "data")}
    data = run_kritarunner(
        pykrita, "krita_setup_driver", "main", tmp_path / "r.json", env, with_repo=False, timeout_s=1200
    )

    assert data["engine_importable_in_krita"] is False  # nothing but the plug-in: the engine is what Set up makes
    before = data["before"]
    assert before["shown"] and before["button"] == "Set up", before
    assert "not set up yet" in before["text"], before
    assert any("not set up yet" in text for level, text in [data["generate_before"]]), data["generate_before"]
    # cancelled while installing: said, and Set up resumes it
    assert any("Installing" in text or "Getting" in text for text in data["first"]), data["first"]
    assert "cancelled" in data["cancelled"]["text"] and data["cancelled"]["button"] == "Resume", data["cancelled"]
    assert data["second"][-1].startswith(f"The shadow engine {__version__} is set up"), data["second"]
    assert not data["after"]["shown"] and "press Generate" in data["after"]["status"][1], data["after"]
    # Generate runs the engine in the environment Set up made in the user's data folder
    engine = data["engine_command"]
    assert Path(engine[0]).is_relative_to(home / "data" / "ssn-shadow" / "engine"), engine
    assert data["names"] == ["Background", "Shadow: Person", "Person"], data
    assert data["messages"][0] == "info" and data["messages"][1].startswith("Shadow "), data["messages"]
    log = (home / "data" / "ssn-shadow" / "setup.log").read_text()
    assert "cancelled" in log and log.rstrip().endswith("done"), log[-2000:]
    # the package is the zip Krita's importer took, unchanged
    assert zipfile.ZipFile(archive).testzip() is None
