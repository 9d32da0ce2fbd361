"""Real GIMP 3 (its chroot, under Xvfb): a frozen worker can be given up within a second, and changes nothing.

The plug-in's engine.json starts tests/hung_worker.py as its shared worker
(the default set-up: a loopback worker the plug-in starts and records); it
answers the cutout's upload and freezes on the dialog's preview and on the
render. Escape pressed in the dialog (its Cancel), and a click on the Cancel
button of GIMP's progress bar in the image window, must each end the filter
within a second, with GIMP's Cancel status, the image as it was, and the
frozen worker's process stopped (at once by the dialog; by the next call after
GIMP's Cancel, which kills the plug-in). Issue #41, defect 15: the filter used
to sit out the client's 120 s timeout with no progress, the dialog dead
meanwhile.
"""

from __future__ import annotations

import contextlib
import json
import os
import shutil
import signal
import tempfile
from pathlib import Path

import pytest
from test_gimp_integration import _exec_scene_then, chroot, run_check  # noqa: F401 - its fixture, shared

from plugin_gimp.install import install
from ssn_engine.host_kit.protocol import PROTOCOL_VERSION

pytestmark = pytest.mark.gimp

HUNG_WORKER = Path(__file__).resolve().parents[1] / "hung_worker.py"
CHECK_SCRIPT = Path(__file__).with_name("gimp_cancel_check.py")
PROGRESS_SCRIPT = Path(__file__).with_name("gimp_progress_cancel_check.py")
FROZEN_SCRIPT = Path(__file__).with_name("gimp_frozen_handshake_check.py")


@pytest.fixture
def frozen(chroot):  # noqa: F811 - the imported fixture
    """A throwaway folder in the chroot with a GIMP profile whose plug-in's shared worker freezes:
    (host path, inner path). Every worker it started is stopped afterwards."""
    work = Path(tempfile.mkdtemp(prefix="ssn-gimp-cancel-", dir=chroot / "tmp"))
    inner = "/tmp/" + work.name  # the same folder seen from inside the chroot
    started: list[int] = []
    try:
        dest = install(work / "profile" / "plug-ins" / "ssn-shadow", python="/usr/bin/python3")
        shutil.copy(HUNG_WORKER, work / "hung_worker.py")
        config = json.loads((dest / "engine.json").read_text())
        config["args"] = [f"{inner}/hung_worker.py", str(PROTOCOL_VERSION), f"{inner}/worker.pid"]
        (dest / "engine.json").write_text(json.dumps(config))  # "shared" as installed: the default set-up
        yield work, inner, started
    finally:
        for pid in started:
            with contextlib.suppress(OSError):
                os.kill(pid, signal.SIGKILL)
        shutil.rmtree(work, ignore_errors=True)


def _run_check(frozen, script: Path, **env: str) -> tuple[dict, str]:
    work, inner, started = frozen
    shutil.copy(script, work / "check.py")
    state = f"{inner}/profile/plug-ins/ssn-shadow/worker.json"
    code = f'OUT_PATH = "{inner}/out.json"; PID_FILE = "{inner}/worker.pid"; STATE_PATH = "{state}"; '
    result, log = run_check(
        inner, code + _exec_scene_then(work, inner, "check.py"), work / "out.json", "GIMP session", **env
    )
    started.extend(call["worker"] for call in (result.get("first"), result.get("second")) if call)
    if (work / "worker.pid").exists():
        started.append(int((work / "worker.pid").read_text()))
    return result, log


def test_the_dialogs_cancel_stops_a_frozen_preview_within_a_second(frozen):
    """Escape in the dialog (its Cancel) while its preview waits on the frozen worker: the dialog still handles
    its events, the filter ends within a second with nothing written, and the worker is stopped at once."""
    result, log = _run_check(frozen, CHECK_SCRIPT, SSN_GIMP_XVFB="1")
    assert result.get("frozen_on") == "preview" and result.get("window"), (result, log[-3000:])
    assert result["status"] == "cancel", result
    waited = result["returned_at"] - result["pressed_at"]
    print(f"Escape pressed to the filter's return: {waited:.2f} s")
    assert 0 < waited < 1.0, result
    assert result["layers_after"] == result["layers_before"] == ["Pawn", "Background"]
    assert result["pawn_unchanged"]
    assert result["worker_alive"] is False, result  # stopped, not left frozen with its one slot taken
    assert "traceback" not in log.lower(), log[-6000:]


def test_gimps_progress_cancel_stops_a_frozen_filter_within_a_second(frozen):
    """The filter, called without its dialog on an image in a window, shows GIMP's progress while the worker
    works; a click on the progress bar's Cancel ends the call within a second (GIMP stops the plug-in). The next
    call stops that frozen worker, which nobody waits for any more, and starts a fresh one."""
    result, log = _run_check(frozen, PROGRESS_SCRIPT, SSN_GIMP_GUI="1")
    first, second = result["first"], result["second"]
    for call in (first, second):
        assert call.get("frozen_on") == "render", (result, log[-3000:])
        width, height = (int(v.split("=")[1]) for v in call["window"] if v.startswith(("WIDTH=", "HEIGHT=")))
        assert [width, height] == result["expected_window"], "the image window moved: update CANCEL in the script"
        assert call["status"] == "cancel", result
        waited = call["returned_at"] - call["clicked_at"]
        print(f"Cancel clicked to the filter's return: {waited:.2f} s")
        assert 0 < waited < 1.0, json.dumps(result)
    assert second["worker"] != first["worker"] and result["first_worker_alive"] is False, result
    assert result["layers_after"] == result["layers_before"] == ["Pawn", "Background"]
    assert result["pawn_unchanged"]


def test_the_call_after_a_worker_froze_whole_stops_it_within_seconds(frozen):
    """The shared worker freezes whole (tests/hung_worker.py --stop: it answers nothing, not even a new
    connection's auth) and GIMP's Cancel kills the call that took it. The next call (Ctrl+F's run mode) stops that
    worker and starts a fresh one in seconds. It used to wait out the client's 120 s socket timeout on the auth
    reply (122 to 124 s, no progress, no Cancel) and leave the frozen worker running."""
    work = frozen[0]
    engine_json = work / "profile" / "plug-ins" / "ssn-shadow" / "engine.json"
    config = json.loads(engine_json.read_text())
    engine_json.write_text(json.dumps({**config, "args": [*config["args"], "--stop"]}))
    result, log = _run_check(frozen, FROZEN_SCRIPT)
    first, second = result["first"], result["second"]
    assert first.get("frozen_on") == "render" and first["status"] != "success", (result, log[-3000:])
    took = second["returned_at"] - second["called_at"]
    print(
        f"the call after a worker froze whole: {took:.2f} s, its fresh worker started after "
        f"{second['started_at'] - second['called_at']:.2f} s"
    )
    assert took < 20.0, json.dumps(result)
    assert second["worker"] != first["worker"] and result["first_worker_alive"] is False, result
    # the fresh worker served the call: after a frozen one, the test's worker answers render with this error
    assert second["status"] == "execution-error" and "started after one froze" in second["error"], second
    assert result["layers_after"] == result["layers_before"] == ["Pawn", "Background"]
    assert result["pawn_unchanged"]
