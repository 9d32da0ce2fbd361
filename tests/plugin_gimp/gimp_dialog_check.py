"""Runs INSIDE GIMP 3 under Xvfb for test_gimp_integration.py: the filter's dialog, interactively.

The plug-in, started with SSN_SHADOW_DIALOG_SELFTEST=1, builds its dialog,
edits the light map, renders the preview and presses OK by itself; this
script calls it with RunMode.INTERACTIVE and reports the outcome as JSON.
"""

import json

import gi

gi.require_version("Gimp", "3.0")
from gi.repository import Gimp  # noqa: E402
from gimp_check_kit import call_filter, layer_names  # noqa: E402

# image, layer: from gimp_pawn_scene.py, exec'd first in the same globals
image, layer = globals()["image"], globals()["layer"]

OUT = globals().get("OUT_PATH", "/tmp/ssn-dialog.json")

result = call_filter(image, layer, Gimp.RunMode.INTERACTIVE)
out = {"status": result.index(0).value_nick, "layers": layer_names(image)}
if result.index(0) != Gimp.PDBStatusType.SUCCESS:
    out["error"] = Gimp.get_pdb().get_last_error()
json.dump(out, open(OUT, "w"))
