"""Runs INSIDE GIMP 3 (gimp-console) for test_gimp_cancel.py: the call after the shared worker froze whole.

The plug-in's engine.json starts tests/hung_worker.py ``--stop`` as its
shared worker: on the first call's render it freezes whole (SIGSTOP), so it
answers nothing any more, not even a new connection's ``auth``. A helper
process then kills that call's plug-in (its process, recorded in worker.json),
as GIMP's Cancel does. The second call, as Ctrl+F makes it (the last
values), must find the recorded worker frozen, stop it and start a fresh one
(which, after a frozen one, answers the render with an error) within seconds:
it used to wait out the client's 120 s socket timeout on the ``auth`` reply,
with no progress and no Cancel, and leave the frozen worker running. Reports,
as JSON, each call's status and times, the workers' process ids, whether the
frozen one still runs, and the layers and the pawn's pixels.
"""

import json
import os
import time

import gi

gi.require_version("Gimp", "3.0")
from gi.repository import Gimp  # noqa: E402
from gimp_check_kit import call_filter, layer_names, pixels, presser_said, process_alive, start_presser  # noqa: E402

# image, layer: from gimp_pawn_scene.py, exec'd first in the same globals; the paths: set by the test
image, layer = globals()["image"], globals()["layer"]
OUT, PID_FILE, STATE = globals()["OUT_PATH"], globals()["PID_FILE"], globals()["STATE_PATH"]

KILL = f"""
import json, signal
plugin = json.load(open({STATE!r}))["client"]
killed = time.time()
os.kill(plugin, signal.SIGKILL)  # what GIMP's Cancel does to the plug-in
print(killed, plugin, open(frozen).read(), flush=True)
"""


def status_of(result):
    status = result.index(0)
    call = {"status": status.value_nick}
    if status != Gimp.PDBStatusType.SUCCESS:
        try:
            call["error"] = Gimp.get_pdb().get_last_error()
        except Exception as exc:  # noqa: BLE001
            call["error"] = f"(no error text: {exc})"
    return call


before, pawn = layer_names(image), pixels(layer)
out = {}
presser = start_presser(PID_FILE, KILL)
first = status_of(call_filter(image, layer, Gimp.RunMode.NONINTERACTIVE, {"light-map": "low-sun-right"}))
first.update(returned_at=time.time(), worker=int(open(PID_FILE).read()))
said = presser_said(presser)
if len(said) == 3:
    first.update(killed_at=float(said[0]), plugin=int(said[1]), frozen_on=said[2])
out["first"] = first
called = time.time()
second = status_of(call_filter(image, layer, Gimp.RunMode.WITH_LAST_VALS))
second.update(called_at=called, returned_at=time.time(), worker=int(open(PID_FILE).read()))
second["started_at"] = os.path.getmtime(PID_FILE)
out["second"] = second
out["first_worker_alive"] = process_alive(first["worker"])
out["layers_before"], out["layers_after"] = before, layer_names(image)
out["pawn_unchanged"] = pixels(layer) == pawn
with open(OUT, "w") as f:
    json.dump(out, f)
