"""Runs INSIDE GIMP 3 (gimp-console) for test_gimp_layers.py: which layers a run replaces, and the layer's opacity.

On copies of the pawn scene (gimp_pawn_scene.py), non-interactively:

- "user": the user's own layer named "Shadow: Pawn" right below "Pawn" (no parasite of the filter's). The
  filter runs on Pawn, again on Pawn, and then on the user's layer itself. Reports the layer stacks (names and
  ids), whether the user's layer is still there with its pixels, and the filter's layers;
- "opacity": Pawn at 100 % and at 50 % opacity, each image's shadow's alpha (its peak and its sum).
"""

import array
import json

import gi

gi.require_version("Gimp", "3.0")
gi.require_version("Gegl", "0.4")
from gi.repository import Gegl, Gimp  # noqa: E402
from gimp_check_kit import call_filter, layer_names, pixels  # noqa: E402

# image, layer: from gimp_pawn_scene.py, exec'd first in the same globals; the path: set by the test
image, layer = globals()["image"], globals()["layer"]
OUT = globals()["OUT_PATH"]
ARGS = {"light-map": "low-sun-right", "opacity": 1.0}


def pawn_of(img):
    return next(lay for lay in img.get_layers() if lay.get_name() == "Pawn")


def run(img, drawable):
    result = call_filter(img, drawable, Gimp.RunMode.NONINTERACTIVE, ARGS)
    call = {"status": result.index(0).value_nick}
    if result.index(0) == Gimp.PDBStatusType.SUCCESS:
        shadow = result.index(1)
        call.update(returned=shadow.get_name(), returned_id=shadow.get_id())
    else:
        call["error"] = Gimp.get_pdb().get_last_error()
    call["layers"] = [[lay.get_name(), lay.get_id()] for lay in img.get_layers()]
    return call


def alpha(drawable):
    rect = Gegl.Rectangle.new(0, 0, drawable.get_width(), drawable.get_height())
    return array.array("f", bytes(drawable.get_buffer().get(rect, 1.0, "A float", Gegl.AbyssPolicy.NONE)))


out = {}
# the user's own "Shadow: Pawn": a grey block (opaque, so it can cast too), right below Pawn
user_image = image.duplicate()
mine = Gimp.Layer.new(user_image, "Shadow: Pawn", 200, 150, Gimp.ImageType.RGBA_IMAGE, 100.0, Gimp.LayerMode.NORMAL)
user_image.insert_layer(mine, None, 1)
px = bytearray(200 * 150 * 4)
for y in range(100, 140):
    px[(y * 200 + 20) * 4 : (y * 200 + 60) * 4] = bytes([90, 90, 90, 255]) * 40
mine.get_buffer().set(Gegl.Rectangle.new(0, 0, 200, 150), "R'G'B'A u8", bytes(px))
mine.get_buffer().flush()
before = pixels(mine)
user = {"mine": mine.get_id(), "before": layer_names(user_image)}
user["runs"] = [run(user_image, pawn_of(user_image)), run(user_image, pawn_of(user_image)), run(user_image, mine)]
user["mine_there"] = any(lay.get_id() == user["mine"] for lay in user_image.get_layers())
user["mine_unchanged"] = user["mine_there"] and pixels(mine) == before
out["user"] = user

# the same pawn at 100 % and at 50 % opacity
opacity = {}
for percent in (100.0, 50.0):
    img = image.duplicate()
    pawn = pawn_of(img)
    pawn.set_opacity(percent)
    result = call_filter(img, pawn, Gimp.RunMode.NONINTERACTIVE, ARGS)
    call = {"status": result.index(0).value_nick}
    if result.index(0) == Gimp.PDBStatusType.SUCCESS:
        values = alpha(result.index(1))
        call.update(peak=max(values), sum=sum(values))
    else:
        call["error"] = Gimp.get_pdb().get_last_error()
    opacity[str(int(percent))] = call
out["opacity"] = opacity
with open(OUT, "w") as f:
    json.dump(out, f)
