"""Static checks of the plug-in folder and the chroot tool (no GIMP needed)."""

import ast
import os
import stat
import subprocess
from pathlib import Path

import pytest


ROOT = Path(__file__).resolve().parents[2]
PLUGIN = ROOT / "plugin_gimp" / "ssn-shadow"
TOOL = ROOT / "tools" / "gimp_chroot.sh"


def test_entry_script_is_executable_gimp_plugin():
    main = PLUGIN / "ssn-shadow.py"
    assert main.stat().st_mode & stat.S_IXUSR
    text = main.read_text()
    assert text.startswith("#!/usr/bin/env python3")
    tree = ast.parse(text)
    classes = [n for n in tree.body if isinstance(n, ast.ClassDef)]
    assert any(ast.unparse(b) == "Gimp.PlugIn" for c in classes for b in c.bases)
    assert "Gimp.main(" in text


def test_plugin_is_thin_no_heavy_imports():
    """GIMP's Python has only GObject introspection: no numpy, no ssn_engine internals beyond the shared copies."""
    for path in PLUGIN.glob("*.py"):
        for node in ast.walk(ast.parse(path.read_text())):
            names = []
            if isinstance(node, ast.Import):
                names = [a.name for a in node.names]
            elif isinstance(node, ast.ImportFrom) and node.module:
                names = [node.module]
            for name in names:
                assert not name.startswith(("numpy", "PIL", "onnxruntime", "skimage")), (path.name, name)
                if name.split(".")[0] == "ssn_engine":
                    assert name.split(".")[:2] == ["ssn_engine", "host_kit"], (path.name, name)


def run_tool(*args, env=None):
    return subprocess.run([str(TOOL), *args], capture_output=True, text=True, env={**os.environ, **(env or {})})


def test_tool_syntax_and_usage():
    assert subprocess.run(["bash", "-n", str(TOOL)]).returncode == 0
    out = run_tool()
    assert out.returncode == 2 and "usage" in out.stderr


def test_tool_status_detects_missing_and_half_built(tmp_path):
    target = tmp_path / "chroot"
    out = run_tool("status", env={"SSN_GIMP_CHROOT": str(target)})
    assert out.returncode == 1 and out.stdout.startswith("missing")
    (target / "usr" / "bin").mkdir(parents=True)  # an interrupted build: no stamp, no gimp
    assert run_tool("status", env={"SSN_GIMP_CHROOT": str(target)}).returncode == 1
    assert run_tool("path", env={"SSN_GIMP_CHROOT": str(target) + "/"}).stdout.strip() == str(target)


@pytest.mark.skipif(os.geteuid() != 0, reason="run refuses without root before checking the chroot")
def test_tool_run_needs_a_ready_chroot(tmp_path):
    out = run_tool("run", "true", env={"SSN_GIMP_CHROOT": str(tmp_path / "none")})
    assert out.returncode == 2 and "build" in out.stderr
