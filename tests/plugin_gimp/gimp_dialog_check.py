"""Runs INSIDE GIMP 3 under Xvfb for test_gimp_integration.py: the filter's dialog, interactively.

The plug-in, started with SSN_SHADOW_DIALOG_SELFTEST=1, builds its dialog,
edits the light map, renders the preview and presses OK by itself; this
script calls it with RunMode.INTERACTIVE and reports the outcome as JSON.
"""

import json

import gi

gi.require_version("Gimp", "3.0")
from gi.repository import Gimp  # noqa: E402

# image, layer: from gimp_pawn_scene.py, exec'd first in the same globals
image, layer = globals()["image"], globals()["layer"]

OUT = globals().get("OUT_PATH", "/tmp/ssn-dialog.json")

proc = Gimp.get_pdb().lookup_procedure("plug-in-ssn-shadow")
config = proc.create_config()
config.set_property("run-mode", Gimp.RunMode.INTERACTIVE)
config.set_property("image", image)
config.set_core_object_array("drawables", [layer])
result = proc.run(config)
out = {"status": result.index(0).value_nick, "layers": [lay.get_name() for lay in image.get_layers()]}
if result.index(0) != Gimp.PDBStatusType.SUCCESS:
    out["error"] = Gimp.get_pdb().get_last_error()
json.dump(out, open(OUT, "w"))
