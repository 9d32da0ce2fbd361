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
import subprocess
import sys
import time

import gi

gi.require_version("Gimp", "3.0")
gi.require_version("Gegl", "0.4")
from gi.repository import Gegl, Gimp  # noqa: E402

# image, layer: from gimp_pawn_scene.py, exec'd first in the same globals; the paths: set by the test
image, layer = globals()["image"], globals()["layer"]
OUT, PID_FILE = globals()["OUT_PATH"], globals()["PID_FILE"]
HANG = 1.5  # seconds the worker hangs before the press

PRESSER = f"""
import os, subprocess, sys, time
frozen = {PID_FILE!r} + ".frozen"
deadline = time.time() + 120
while not os.path.exists(frozen) and time.time() < deadline:
    time.sleep(0.05)
time.sleep({HANG})
def xdotool(*args):
    return subprocess.run(["xdotool", *args], capture_output=True, text=True, timeout=20).stdout.split()
window = xdotool("search", "--onlyvisible", "--name", "Soft Shadow")
if window:
    xdotool("windowfocus", "--sync", window[0])
pressed = time.time()
xdotool("key", "--clearmodifiers", "Escape")
print(pressed, window[0] if window else "", open(frozen).read(), flush=True)
"""


def pixels(drawable):
    rect = Gegl.Rectangle.new(0, 0, drawable.get_width(), drawable.get_height())
    return bytes(drawable.get_buffer().get(rect, 1.0, "R'G'B'A u8", Gegl.AbyssPolicy.NONE))


def names():
    return [lay.get_name() for lay in image.get_layers()]


def alive(pid):
    try:
        with open(f"/proc/{pid}/stat") as f:
            return f.read().rsplit(")", 1)[1].split()[0] != "Z"
    except FileNotFoundError:
        return False


before, pawn = names(), pixels(layer)
presser = subprocess.Popen([sys.executable, "-c", PRESSER], stdout=subprocess.PIPE, text=True)
proc = Gimp.get_pdb().lookup_procedure("plug-in-ssn-shadow")
config = proc.create_config()
config.set_property("run-mode", Gimp.RunMode.INTERACTIVE)
config.set_property("image", image)
config.set_core_object_array("drawables", [layer])
result = proc.run(config)
returned = time.time()
out = {"status": result.index(0).value_nick, "returned_at": returned}
try:
    said = presser.communicate(timeout=30)[0].split()
except subprocess.TimeoutExpired:
    presser.kill()
    said = []
if len(said) == 3:
    out.update(pressed_at=float(said[0]), window=said[1], frozen_on=said[2])
out["layers_before"], out["layers_after"] = before, names()
out["pawn_unchanged"] = pixels(layer) == pawn
if os.path.exists(PID_FILE):
    pid = int(open(PID_FILE).read())
    time.sleep(0.2)
    out["worker_alive"] = alive(pid)
with open(OUT, "w") as f:
    json.dump(out, f)
