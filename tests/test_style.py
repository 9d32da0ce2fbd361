"""The tree stays linted, formatted (ruff) and type-checked (pyright, basic, over the engine and both plug-ins,
with typings/ for the Krita API and GObject introspection), as configured in pyproject.toml: a slip fails the
tests, not a review."""

import shutil
import subprocess
import sys
from pathlib import Path

import pytest

REPO = Path(__file__).resolve().parents[1]


def _ruff(*args: str) -> subprocess.CompletedProcess:
    exe = shutil.which("ruff")
    command = [exe] if exe else [sys.executable, "-m", "ruff"]
    return subprocess.run([*command, *args], cwd=REPO, capture_output=True, text=True, timeout=300)


@pytest.mark.parametrize("args", [("check", "."), ("format", "--check", ".")], ids=["lint", "format"])
def test_ruff(args):
    result = _ruff(*args)
    assert result.returncode == 0, result.stdout[-3000:] + result.stderr[-2000:]


def test_pyright():
    exe = shutil.which("pyright")
    command = [exe] if exe else [sys.executable, "-m", "pyright"]
    result = subprocess.run(command, cwd=REPO, capture_output=True, text=True, timeout=600)
    assert result.returncode == 0, result.stdout[-4000:] + result.stderr[-2000:]
