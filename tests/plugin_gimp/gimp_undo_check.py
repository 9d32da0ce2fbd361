"""Runs INSIDE the GIMP 3 GUI (gimp-3.0 under Xvfb) for test_gimp_integration.py: one undo removes the shadow.

GIMP 3's PDB has no undo command, so this presses Ctrl+Z for real: it shows
the image in a display, calls plug-in-ssn-shadow, focuses the image window
with xdotool and sends the key through XTEST, then reports the layer stack
before, after the filter and after the single undo, as JSON.
"""

import json
import subprocess
import time

import gi

gi.require_version("Gimp", "3.0")
from gi.repository import Gimp  # noqa: E402

# image, layer: from gimp_pawn_scene.py, exec'd first in the same globals
image, layer = globals()["image"], globals()["layer"]

OUT = globals().get("OUT_PATH", "/tmp/ssn-undo.json")
out = {}


def report(key, value):
    out[key] = value
    with open(OUT, "w") as f:
        json.dump(out, f)


def names(image):
    return [lay.get_name() for lay in image.get_layers()]


def xdotool(*args):
    return subprocess.run(["xdotool", *args], capture_output=True, text=True, timeout=20)


layer.get_buffer().flush()
image.clean_all()
Gimp.Display.new(image)
Gimp.displays_flush()
report("before", names(image))

proc = Gimp.get_pdb().lookup_procedure("plug-in-ssn-shadow")
config = proc.create_config()
config.set_property("run-mode", Gimp.RunMode.NONINTERACTIVE)
config.set_property("image", image)
config.set_core_object_array("drawables", [layer])
config.set_property("light-map", "low-sun-right")
report("status", proc.run(config).index(0).value_nick)
Gimp.displays_flush()
report("after", names(image))

window = None
for _ in range(40):  # the image window's title lists its layers
    found = xdotool("search", "--onlyvisible", "--name", r"\[Untitled\].*layers").stdout.split()
    if found:
        window = found[0]
        break
    time.sleep(0.25)
report("window", window)
if window:
    xdotool("windowfocus", "--sync", window)
    report("focused", xdotool("getwindowfocus", "getwindowname").stdout.strip())
    time.sleep(0.3)
    xdotool("key", "--clearmodifiers", "ctrl+z")  # exactly one undo
    undone = names(image)
    for _ in range(40):
        time.sleep(0.25)
        undone = names(image)
        if undone != out["after"]:
            break
    time.sleep(0.5)  # let a (wrong) second step show up, if any
    report("after_undo", names(image))
