"""Real GIMP 3 (its chroot, under Xvfb): a frozen worker can be given up within a second, and changes nothing.

The plug-in's engine.json starts tests/hung_worker.py as its shared worker
(the default set-up: a loopback worker the plug-in starts and records); it
answers the cutout's upload and freezes on the dialog's preview. Escape
pressed in the dialog (its Cancel) must end the filter within a second, with
GIMP's Cancel status, the image as it was and the frozen worker's process
stopped (issue #41, defect 15: the filter used to sit out the client's 120 s
timeout, the dialog dead meanwhile).
"""

from __future__ import annotations

import json
import shutil
import tempfile
from pathlib import Path

import pytest
from test_gimp_integration import IN_CI, SCENE_SCRIPT, _chroot_dir, _exec_scene_then, run_gimp

from plugin_gimp.install import install
from ssn_engine.host_kit.protocol import PROTOCOL_VERSION

pytestmark = pytest.mark.gimp

HUNG_WORKER = Path(__file__).resolve().parents[1] / "hung_worker.py"
CHECK_SCRIPT = Path(__file__).with_name("gimp_cancel_check.py")


@pytest.fixture(scope="module")
def chroot() -> Path:
    path = _chroot_dir()
    if path is None:
        if IN_CI:
            pytest.fail("CI=true: the GIMP 3 chroot could not be built (needs root, debootstrap and the network)")
        pytest.skip("no GIMP 3 chroot and it cannot be built here (needs root and debootstrap)")
    return path


def test_the_dialogs_cancel_stops_a_frozen_preview_within_a_second(chroot):
    work = Path(tempfile.mkdtemp(prefix="ssn-gimp-cancel-", dir=chroot / "tmp"))
    inner = "/tmp/" + work.name  # the same folder seen from inside the chroot
    try:
        dest = install(work / "profile" / "plug-ins" / "ssn-shadow", python="/usr/bin/python3")
        shutil.copy(HUNG_WORKER, work / "hung_worker.py")
        shutil.copy(CHECK_SCRIPT, work / "cancel.py")
        shutil.copy(SCENE_SCRIPT, work / "scene.py")
        config = json.loads((dest / "engine.json").read_text())
        config["args"] = [f"{inner}/hung_worker.py", str(PROTOCOL_VERSION), f"{inner}/worker.pid"]
        (dest / "engine.json").write_text(json.dumps(config))  # "shared" as installed: the default set-up
        code = f'OUT_PATH = "{inner}/cancel.json"; PID_FILE = "{inner}/worker.pid"; '
        run, seconds = run_gimp(inner, code + _exec_scene_then(inner, "cancel.py"), SSN_GIMP_XVFB="1")
        log = run.stdout + run.stderr
        print(f"\ngimp-console cancel session: {seconds:.1f} s")
        assert (work / "cancel.json").exists(), log[-6000:]
        result = json.loads((work / "cancel.json").read_text())
        assert result.get("frozen_on") == "preview" and result.get("window"), (result, log[-3000:])
        assert result["status"] == "cancel", result
        waited = result["returned_at"] - result["pressed_at"]
        print(f"Escape pressed to the filter's return: {waited:.2f} s")
        assert 0 < waited < 1.0, result
        assert result["layers_after"] == result["layers_before"] == ["Pawn", "Background"]
        assert result["pawn_unchanged"]
        assert result["worker_alive"] is False, result  # stopped, not left frozen with its one slot taken
        assert "traceback" not in log.lower(), log[-6000:]
    finally:
        shutil.rmtree(work, ignore_errors=True)
