"""Runs INSIDE the GIMP 3 GUI (gimp-3.0 under Xvfb) for test_gimp_cancel.py: GIMP's own Cancel, in the image
window's progress bar, while the filter waits on a frozen worker; twice.

The plug-in's engine.json starts tests/hung_worker.py as its shared worker,
which freezes on ``render``. The image is shown in a display and the filter
called non-interactively; a helper process waits for the worker to freeze,
lets it hang a moment, notes the time and clicks the Cancel button of the
progress bar in the image window's status bar for real (xdotool, XTEST).
GIMP then stops the plug-in. The second call must stop the first call's
frozen worker (nobody waits for it) and start a fresh one, which freezes
too and is cancelled the same way. Reports, as JSON, each call's status,
the times of the click and of the return, the workers' process ids, whether
the first one still runs, and whether the layers and the pawn's pixels are
as before.
"""

import json
import os
import time

import gi

gi.require_version("Gimp", "3.0")
from gi.repository import Gimp  # noqa: E402
from gimp_check_kit import (  # noqa: E402
    call_filter,
    layer_names,
    pixels,
    presser_said,
    process_alive,
    show,
    start_presser,
)

# image, layer: from gimp_pawn_scene.py, exec'd first in the same globals; the paths: set by the test
image, layer = globals()["image"], globals()["layer"]
OUT, PID_FILE = globals()["OUT_PATH"], globals()["PID_FILE"]
# GIMP 3.0.4's image window on a 1280 x 1024 Xvfb screen without a window manager: 800 x 600 at the origin, the
# status bar's Cancel button (shown while a progress runs) at this point of it
WINDOW, CANCEL = (800, 600), (519, 582)

CLICK = f"""
window = xdotool("search", "--onlyvisible", "--name", "[[]Untitled[]].*layers")
size = xdotool("getwindowgeometry", "--shell", window[0]) if window else []
clicked = time.time()
# no --sync: the pointer may be there already (the call before), and xdotool would wait for it to get there
xdotool("mousemove", *map(str, {CANCEL!r}), "sleep", "0.05", "click", "1")
print(clicked, open(frozen).read(), " ".join(size), flush=True)
"""


def cancelled_call():
    """One call of the filter, cancelled by a click on GIMP's progress bar once the worker has frozen."""
    if os.path.exists(PID_FILE + ".frozen"):
        os.remove(PID_FILE + ".frozen")
    presser = start_presser(PID_FILE, CLICK)
    called = time.time()
    result = call_filter(image, layer, Gimp.RunMode.NONINTERACTIVE, {"light-map": "low-sun-right"})
    call = {"status": result.index(0).value_nick, "returned_at": time.time(), "worker": int(open(PID_FILE).read())}
    call.update(started_at=os.path.getmtime(PID_FILE), called_at=called)
    if os.path.exists(PID_FILE + ".frozen"):
        call["frozen_at"] = os.path.getmtime(PID_FILE + ".frozen")
    said = presser_said(presser)
    if len(said) >= 2:
        call.update(clicked_at=float(said[0]), frozen_on=said[1], window=said[2:])
    return call


show(image, layer)
before, pawn = layer_names(image), pixels(layer)
out = {"expected_window": list(WINDOW)}
out["first"] = cancelled_call()
Gimp.displays_flush()
out["second"] = cancelled_call()
out["first_worker_alive"] = process_alive(out["first"]["worker"])
out["layers_before"], out["layers_after"] = before, layer_names(image)
out["pawn_unchanged"] = pixels(layer) == pawn
with open(OUT, "w") as f:
    json.dump(out, f)
