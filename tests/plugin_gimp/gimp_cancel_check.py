"""Runs INSIDE GIMP 3 under Xvfb for test_gimp_cancel.py: the dialog's Cancel while its preview waits on a frozen
worker.

The plug-in's engine.json starts tests/hung_worker.py, which answers the
cutout's upload and freezes on the preview. A helper process waits for it to
freeze, lets it hang a moment, then presses Escape (the dialog's Cancel) in
the dialog window for real (xdotool, XTEST) and notes the time; this script
calls the filter interactively and reports, as JSON, how long after the press
it returned, its status, whether the layers and the pawn's pixels are as
before, and whether the worker process is still there.
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
OUT, PID_FILE = globals()["OUT_PATH"], globals()["PID_FILE"]

ESCAPE = """
window = xdotool("search", "--onlyvisible", "--name", "Soft Shadow")
if window:
    xdotool("windowfocus", "--sync", window[0])
pressed = time.time()
xdotool("key", "--clearmodifiers", "Escape")
print(pressed, window[0] if window else "", open(frozen).read(), flush=True)
"""

before, pawn = layer_names(image), pixels(layer)
presser = start_presser(PID_FILE, ESCAPE)
result = call_filter(image, layer, Gimp.RunMode.INTERACTIVE)
returned = time.time()
out = {"status": result.index(0).value_nick, "returned_at": returned}
said = presser_said(presser)
if len(said) == 3:
    out.update(pressed_at=float(said[0]), window=said[1], frozen_on=said[2])
out["layers_before"], out["layers_after"] = before, layer_names(image)
out["pawn_unchanged"] = pixels(layer) == pawn
if os.path.exists(PID_FILE):
    pid = int(open(PID_FILE).read())
    time.sleep(0.2)
    out["worker_alive"] = process_alive(pid)
with open(OUT, "w") as f:
    json.dump(out, f)
