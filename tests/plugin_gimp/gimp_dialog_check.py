"""Runs INSIDE GIMP 3 under Xvfb for test_gimp_integration.py: the filter's dialog, interactively.

The plug-in, started with SSN_SHADOW_DIALOG_SELFTEST=1, builds its dialog,
edits the light map, renders the preview and presses OK by itself; this
script calls it with RunMode.INTERACTIVE and reports the outcome as JSON.
"""

import json

import gi

gi.require_version("Gimp", "3.0")
gi.require_version("Gegl", "0.4")
from gi.repository import Gegl, Gimp  # noqa: E402

OUT = globals().get("OUT_PATH", "/tmp/ssn-dialog.json")

Gegl.init(None)
image = Gimp.Image.new(200, 150, Gimp.ImageBaseType.RGB)
bg = Gimp.Layer.new(image, "Background", 200, 150, Gimp.ImageType.RGB_IMAGE, 100.0, Gimp.LayerMode.NORMAL)
image.insert_layer(bg, None, 0)
bg.fill(Gimp.FillType.WHITE)
layer = Gimp.Layer.new(image, "Pawn", 200, 150, Gimp.ImageType.RGBA_IMAGE, 100.0, Gimp.LayerMode.NORMAL)
image.insert_layer(layer, None, 0)
px = bytearray(200 * 150 * 4)
for y in range(20, 130):
    px[(y * 200 + 85) * 4 : (y * 200 + 115) * 4] = bytes([30, 30, 200, 255]) * 30
layer.get_buffer().set(Gegl.Rectangle.new(0, 0, 200, 150), "R'G'B'A u8", bytes(px))
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
