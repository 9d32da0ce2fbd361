"""Runs INSIDE GIMP 3 before gimp_dialog_check.py / gimp_undo_check.py: the scene they share.

Defines ``image`` (200 x 150 RGB, white "Background") and ``layer`` ("Pawn", RGBA, a
blue 30 x 110 px bar with transparent surroundings) in the globals of the exec'd script;
``SCENE_PRECISION`` (a Gimp.Precision name), if defined, converts the image to it.
"""

import gi

gi.require_version("Gimp", "3.0")
gi.require_version("Gegl", "0.4")
from gi.repository import Gegl, Gimp  # noqa: E402

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
layer.get_buffer().flush()
if globals().get("SCENE_PRECISION"):
    image.convert_precision(getattr(Gimp.Precision, SCENE_PRECISION))  # noqa: F821 - set by the test
