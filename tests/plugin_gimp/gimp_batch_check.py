"""Runs INSIDE GIMP 3 (python-fu-eval) for test_gimp_integration.py; GIMP's Python, no pytest.

Reads a JSON job (cases, paths) from the path in ``JOB``, builds each case's
image, calls plug-in-ssn-shadow non-interactively (lookup_procedure,
create_config, run) and writes what it observed (layer stack, offsets, pixels,
the source layer and selection before and after, status, error text, timing)
as JSON for the test to check. Pixel arrays travel as files of raw float32.
"""

import array
import json
import time
import traceback

import gi

gi.require_version("Gimp", "3.0")
gi.require_version("Gegl", "0.4")
gi.require_version("Babl", "0.1")
from gi.repository import Babl, Gegl, Gimp  # noqa: E402

JOB = globals().get("JOB_PATH", "/tmp/ssn-gimp-job/job.json")


def read(drawable_or_buffer, x, y, w, h, fmt):
    buffer = drawable_or_buffer.get_buffer() if hasattr(drawable_or_buffer, "get_buffer") else drawable_or_buffer
    return bytes(buffer.get(Gegl.Rectangle.new(x, y, w, h), 1.0, fmt, Gegl.AbyssPolicy.NONE))


def build(case):
    w, h = case["width"], case["height"]
    base = getattr(Gimp.ImageBaseType, case["base"])
    precision = getattr(Gimp.Precision, case["precision"])
    image = Gimp.Image.new_with_precision(w, h, base, precision)
    rgb = case["base"] == "RGB"
    bg = Gimp.Layer.new(
        image,
        "Background",
        w,
        h,
        Gimp.ImageType.RGB_IMAGE if rgb else Gimp.ImageType.GRAY_IMAGE,
        100.0,
        Gimp.LayerMode.NORMAL,
    )
    image.insert_layer(bg, None, 0)
    bg.fill(Gimp.FillType.WHITE)
    c = case["cutout"]
    has_alpha = c.get("alpha", True)
    ltype = (
        (Gimp.ImageType.RGBA_IMAGE if has_alpha else Gimp.ImageType.RGB_IMAGE)
        if rgb
        else (Gimp.ImageType.GRAYA_IMAGE if has_alpha else Gimp.ImageType.GRAY_IMAGE)
    )
    layer = Gimp.Layer.new(image, c["name"], c["w"], c["h"], ltype, 100.0, Gimp.LayerMode.NORMAL)
    parent = None
    if case.get("locked_group"):  # the cutout inside a group whose contents are locked
        parent = Gimp.GroupLayer.new(image, "Locked group")
        image.insert_layer(parent, None, 0)
    image.insert_layer(layer, parent, 0)
    layer.set_offsets(c["x"], c["y"])
    # the cutout: opaque red-ish blocks (rect, or rects: several objects, in layer coordinates), transparent elsewhere
    px = bytearray(c["w"] * c["h"] * 4)
    for x0, y0, x1, y1 in c.get("rects", [c["rect"]]):
        for yy in range(y0, y1):
            row = yy * c["w"] * 4
            px[row + x0 * 4 : row + x1 * 4] = bytes([200, 60, 40, 255]) * (x1 - x0)
    if not has_alpha:
        layer.fill(Gimp.FillType.WHITE)
    layer.get_buffer().set(Gegl.Rectangle.new(0, 0, c["w"], c["h"]), "R'G'B'A u8", bytes(px))
    layer.get_buffer().flush()
    if case.get("mask_right_half"):  # a layer mask hiding the right half of the layer
        mask = layer.create_mask(Gimp.AddMaskType.WHITE)
        layer.add_mask(mask)
        half = c["w"] // 2
        mask.get_buffer().set(
            Gegl.Rectangle.new(half, 0, c["w"] - half, c["h"]), "Y u8", bytes((c["w"] - half) * c["h"])
        )
        mask.get_buffer().flush()
    if case.get("select"):
        sx, sy, sw, sh = case["select"]
        if sw == sh == 1:
            image.select_rectangle(Gimp.ChannelOps.REPLACE, sx, sy, 1, 1)
        else:
            image.select_ellipse(Gimp.ChannelOps.REPLACE, sx, sy, sw, sh)
    if case.get("indexed"):
        image.convert_indexed(Gimp.ConvertDitherType.NONE, Gimp.ConvertPaletteType.GENERATE, 16, False, False, "")
    if case.get("hidden"):
        layer.set_visible(False)
    if "layer_opacity" in case:
        layer.set_opacity(case["layer_opacity"])
    if parent is not None:
        parent.set_lock_content(True)  # last: nothing may write into the group after this
    return image, layer


def run_case(case, out_dir):
    image, layer = build(case)
    w, h = image.get_width(), image.get_height()
    res = {"name": case["id"]}
    # the alpha the plug-in should cast from: the selection if any, else the layer alpha on the canvas
    ox, oy = layer.get_offsets()[1:]
    if Gimp.Selection.bounds(image)[1]:
        cutout = read(image.get_selection(), 0, 0, w, h, "Y float")
    else:
        cutout = read(layer, -ox, -oy, w, h, "A float")
        if layer.get_mask() is not None:  # what shows: the alpha times the mask
            alpha = array.array("f", cutout)
            mask = array.array("f", read(layer.get_mask(), -ox, -oy, w, h, "Y float"))
            cutout = array.array("f", (a * m for a, m in zip(alpha, mask, strict=True))).tobytes()
    with open(f"{out_dir}/{case['id']}.cutout.f32", "wb") as f:
        f.write(cutout)
    res["cutout_pixels"] = f"{out_dir}/{case['id']}.cutout.f32"
    src_before = read(layer, 0, 0, layer.get_width(), layer.get_height(), "R'G'B'A float")
    sel_before = read(image.get_selection(), 0, 0, w, h, "Y float")
    layers_before = [lay.get_name() for lay in image.get_layers()]
    pdb = Gimp.get_pdb()
    proc = pdb.lookup_procedure("plug-in-ssn-shadow")
    res["registered"] = proc is not None
    if proc is None:
        return res
    config = proc.create_config()
    config.set_property("run-mode", Gimp.RunMode.NONINTERACTIVE)
    config.set_property("image", image)
    config.set_core_object_array("drawables", [layer])
    for key, value in case["args"].items():
        if key == "shadow-color":
            color = Gegl.Color.new("black")
            color.set_rgba_with_space(value[0], value[1], value[2], 1.0, Babl.space("sRGB"))
            value = color
        config.set_property(key, value)
    t = time.time()
    result = proc.run(config)
    res["seconds"] = time.time() - t
    res["reruns"] = []
    for target in case.get("reruns", []):  # run again on the shadow just made, or on the source
        drawable = result.index(1) if target == "shadow" else layer
        config.set_core_object_array("drawables", [drawable])
        result = proc.run(config)
        res["reruns"].append(
            {
                "status": result.index(0).value_nick,
                "layers": [lay.get_name() for lay in image.get_layers()],
                "selected": [lay.get_name() for lay in image.get_selected_layers()],
                "returned": result.index(1).get_name(),
                "returned_is_selected": [x.get_id() for x in image.get_selected_layers()] == [result.index(1).get_id()],
            }
        )
    status = result.index(0)
    res["status"] = status.value_nick
    if status != Gimp.PDBStatusType.SUCCESS:
        try:
            res["error"] = pdb.get_last_error()
        except Exception as exc:  # noqa: BLE001
            res["error"] = f"(no error text: {exc})"
    layers = image.get_layers()
    res["selected_after"] = [lay.get_name() for lay in image.get_selected_layers()]
    res["layers_before"] = layers_before
    res["layers_after"] = [lay.get_name() for lay in layers]
    res["source_unchanged"] = read(layer, 0, 0, layer.get_width(), layer.get_height(), "R'G'B'A float") == src_before
    res["source_offsets"] = list(layer.get_offsets()[1:])
    res["selection_unchanged"] = read(image.get_selection(), 0, 0, w, h, "Y float") == sel_before
    res["undo_enabled"] = image.undo_is_enabled()
    if status == Gimp.PDBStatusType.SUCCESS:
        shadow = result.index(1)
        res["returned_layer"] = shadow.get_name() if shadow else None
        res["shadow_name"] = shadow.get_name()
        res["shadow_mode"] = shadow.get_mode().value_nick
        res["shadow_offsets"] = list(shadow.get_offsets()[1:])
        res["shadow_size"] = [shadow.get_width(), shadow.get_height()]
        res["shadow_position"] = image.get_item_position(shadow)
        res["source_position"] = image.get_item_position(layer)
        res["shadow_format"] = Babl.format_get_encoding(shadow.get_format())
        sw, sh = shadow.get_width(), shadow.get_height()
        path = f"{out_dir}/{case['id']}.shadow.f32"
        with open(path, "wb") as f:
            f.write(read(shadow, 0, 0, sw, sh, "R'G'B'A float"))
        res["shadow_pixels"] = path
    image.delete()
    return res


def main():
    job = json.load(open(JOB))
    Gegl.init(None)
    results = []
    for case in job["cases"]:
        try:
            results.append(run_case(case, job["out_dir"]))
        except Exception:  # noqa: BLE001
            results.append({"name": case["id"], "exception": traceback.format_exc()})
    with open(job["out_dir"] + "/results.json", "w") as f:
        json.dump(results, f, indent=1)


main()
