"""Runs INSIDE GIMP 3 under Xvfb (python-fu-eval) for test_gimp_dialog_controls.py: the dialog's controls.

Opens the filter's dialog (RunMode.INTERACTIVE) once per run of ``wide()`` below (of ``narrow()`` where the code
before this script sets ``RUN_SET = "narrow"``), each time on the image the run names; before each it writes the
run to ``steps.json`` beside this script, where the plug-in's side of the test
(gimp_dialog_steps.py, started by SSN_SHADOW_DIALOG_SELFTEST) reads what to do; that side appends what it saw to
``out/steps.jsonl``. This side appends each run's outcome (status, layers, the image's camera record) to
``out/runs.jsonl``.
"""

import json
import os
import traceback

import gi

gi.require_version("Gimp", "3.0")
gi.require_version("Gegl", "0.4")
from gi.repository import Gegl, Gimp  # noqa: E402
from gimp_check_kit import call_filter, layer_names  # noqa: E402

HERE = os.path.dirname(globals().get("SCRIPT_PATH", "/tmp/ssn-controls/check.py"))
LONG_NAME = "Pawn cut out of the holiday photograph " + "x" * 120  # one long word: it must wrap too


def make_image(width, height, name="Pawn", opaque=True):
    """A white background and a layer ``name`` holding a dark bar standing on the ground (transparent around it,
    or wholly transparent without ``opaque``)."""
    Gegl.init(None)
    image = Gimp.Image.new(width, height, Gimp.ImageBaseType.RGB)
    bg = Gimp.Layer.new(image, "Background", width, height, Gimp.ImageType.RGB_IMAGE, 100.0, Gimp.LayerMode.NORMAL)
    image.insert_layer(bg, None, 0)
    bg.fill(Gimp.FillType.WHITE)
    layer = Gimp.Layer.new(image, name, width, height, Gimp.ImageType.RGBA_IMAGE, 100.0, Gimp.LayerMode.NORMAL)
    image.insert_layer(layer, None, 0)
    px = bytearray(width * height * 4)
    if opaque:
        x0, x1, y0, y1 = int(0.42 * width), int(0.58 * width), int(0.2 * height), int(0.85 * height)
        for y in range(y0, y1):
            px[(y * width + x0) * 4 : (y * width + x1) * 4] = bytes([30, 30, 200, 255]) * (x1 - x0)
    layer.get_buffer().set(Gegl.Rectangle.new(0, 0, width, height), "R'G'B'A u8", bytes(px))
    layer.get_buffer().flush()
    return image, layer


def run(name, image, layer, **task):
    with open(os.path.join(HERE, "steps.json"), "w") as f:
        json.dump({"run": name, **task}, f)
    out = {"run": name}
    try:
        result = call_filter(image, layer, Gimp.RunMode.INTERACTIVE)
        out["status"] = result.index(0).value_nick
        out["layers"] = layer_names(image)
        parasite = image.get_parasite("ssn-shadow-camera")
        out["camera_record"] = bytes(parasite.get_data()).decode() if parasite is not None else None
        if name.startswith("geometry"):
            parasite = image.get_parasite("ssn-shadow-geometry")
            out["geometry_record"] = bytes(parasite.get_data()).decode() if parasite is not None else None
    except Exception:  # noqa: BLE001 - report it to the test
        out["exception"] = traceback.format_exc()
    with open(os.path.join(HERE, "out", "runs.jsonl"), "a") as f:
        f.write(json.dumps(out) + "\n")


def narrow():
    """On a 768 x 1366 portrait screen: the layout runs alone."""
    portrait, portrait_layer = make_image(480, 640)
    run("layout", portrait, portrait_layer)
    landscape, landscape_layer = make_image(640, 480)
    run("layout", landscape, landscape_layer)


def wide():
    """On a 1366 x 768 screen: every run."""
    pawn, pawn_layer = make_image(320, 240)
    run("reset", pawn, pawn_layer)
    run("lights", pawn, pawn_layer)
    selected, selected_layer = make_image(320, 240)
    selected.select_rectangle(Gimp.ChannelOps.REPLACE, 20, 30, 100, 60)  # a selection left over from other work
    run("selection", selected, selected_layer)

    portrait, portrait_layer = make_image(480, 640)
    run("layout", portrait, portrait_layer)
    landscape, landscape_layer = make_image(640, 480)
    run("layout", landscape, landscape_layer)
    faint, faint_layer = make_image(480, 640, LONG_NAME, opaque=False)
    run("layout", faint, faint_layer)

    # the horizon: from a guide and by clicking the preview on one image, not carried to another, kept (and
    # scaled) with the first
    first, first_layer = make_image(640, 480)
    first.add_hguide(300)
    run("horizon-first", first, first_layer)
    second, second_layer = make_image(1600, 1200)
    run("horizon-second", second, second_layer)
    first.scale(1280, 960)
    run("horizon-again", first, first_layer)

    # the lift and thickness: set, kept with the image, reset; not carried to another image
    lifted, lifted_layer = make_image(320, 240)
    run("geometry", lifted, lifted_layer)
    run("geometry-again", lifted, lifted_layer)
    other, other_layer = make_image(320, 240)
    run("geometry-other", other, other_layer)


if globals().get("RUN_SET") == "narrow":
    narrow()
else:
    wide()
