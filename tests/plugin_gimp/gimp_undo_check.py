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
from gimp_check_kit import call_filter, layer_names, show  # noqa: E402

# image, layer: from gimp_pawn_scene.py, exec'd first in the same globals
image, layer = globals()["image"], globals()["layer"]

OUT = globals().get("OUT_PATH", "/tmp/ssn-undo.json")
out = {}


def report(key, value):
    out[key] = value
    with open(OUT, "w") as f:
        json.dump(out, f)


def xdotool(*args):
    return subprocess.run(["xdotool", *args], capture_output=True, text=True, timeout=20)


show(image, layer)
report("before", layer_names(image))
result = call_filter(image, layer, Gimp.RunMode.NONINTERACTIVE, {"light-map": "low-sun-right"})
report("status", result.index(0).value_nick)
Gimp.displays_flush()
report("after", layer_names(image))

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
    undone = layer_names(image)
    for _ in range(40):
        time.sleep(0.25)
        undone = layer_names(image)
        if undone != out["after"]:
            break
    time.sleep(0.5)  # let a (wrong) second step show up, if any
    report("after_undo", layer_names(image))
