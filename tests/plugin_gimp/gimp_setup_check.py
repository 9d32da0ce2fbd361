"""Runs INSIDE GIMP 3 under Xvfb for test_gimp_integration.py: the packaged plug-in, with no engine set up.

A non-interactive call first (it must say how to set up and change nothing), then an interactive one: the
plug-in's Set up dialog (its SSN_SHADOW_SETUP_TEST script presses Set up), the engine set up inside this
system, then the filter's dialog (SSN_SHADOW_DIALOG_SELFTEST=1 presses OK) and the shadow layer.
"""

import json

import gi

gi.require_version("Gimp", "3.0")
from gi.repository import Gimp  # noqa: E402
from gimp_check_kit import call_filter, layer_names  # noqa: E402

image, layer = globals()["image"], globals()["layer"]
OUT = globals().get("OUT_PATH", "/tmp/ssn-setup.json")

out = {}
batch = call_filter(image, layer, Gimp.RunMode.NONINTERACTIVE)
out["batch"] = {
    "status": batch.index(0).value_nick,
    "error": Gimp.get_pdb().get_last_error(),
    "layers": layer_names(image),
}
result = call_filter(image, layer, Gimp.RunMode.INTERACTIVE)
out["status"] = result.index(0).value_nick
out["layers"] = layer_names(image)
if result.index(0) != Gimp.PDBStatusType.SUCCESS:
    out["error"] = Gimp.get_pdb().get_last_error()
json.dump(out, open(OUT, "w"))
