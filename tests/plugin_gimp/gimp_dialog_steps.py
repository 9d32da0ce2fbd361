"""Runs INSIDE the filter's own process (GIMP's Python, under Xvfb) for test_gimp_dialog_controls.py.

The plug-in, started with SSN_SHADOW_DIALOG_SELFTEST=<this file>, runs it once its dialog shows, with ``parts``
(dialog, config, host, preview, area, presets). It reads the run to do from ``steps.json`` beside it (written by
gimp_dialog_controls_check.py), works the dialog as a user would, with real pointer events (xdotool on the Xvfb
display: drags on the light map, clicks on the preview, the From guide button, the horizon box, Reset and its
popover's items), appends what it saw to ``out/steps.jsonl`` and presses OK or Cancel.
"""

import json
import os
import re
import subprocess
import traceback

import gi

gi.require_version("Gtk", "3.0")
from gi.repository import GLib, GObject, Gtk  # noqa: E402

parts = globals()["parts"]
HERE = os.path.dirname(os.path.abspath(__file__))
TASK = json.load(open(os.path.join(HERE, "steps.json")))
RESET = 1  # GimpProcedureDialog's response id of its Reset button
NOTE = re.compile(r"horizon at row (-?\d+) \([^)]*\), (\d+)° field of view")
record = {"run": TASK["run"]}


def widget(name):
    return parts.dialog.get_widget(name, GObject.TYPE_NONE)


def snapshot():
    """What the user sees: the preset box, the map, the camera fields (and whether they take input), the note."""
    config, status = parts.config, parts.preview.status
    note = NOTE.search(status.get_text())
    window = parts.dialog.get_window()
    intensity = getattr(parts.area, "intensity_box", None)  # (None: a plug-in without these, for a control run)
    layout = getattr(parts, "layout", None)
    return {
        "label": parts.presets.get_active_text(),
        "map": parts.area.editor.lights.to_dict(),
        "use": config.get_property("use-horizon"),
        "horizon": config.get_property("horizon"),
        "fov": config.get_property("fov"),
        "note": status.get_text(),
        "note_camera": [int(note[1]), int(note[2])] if note else None,
        "note_lines": status.get_layout().get_line_count(),
        "row_sensitive": widget("horizon").is_sensitive(),
        "fov_sensitive": widget("fov").is_sensitive(),
        "size": [window.get_width(), window.get_height()],
        "preview": [parts.preview.widget.get_allocated_width(), parts.preview.widget.get_allocated_height()],
        "target": next(text for text in label_texts() if text.startswith("Casting the shadow")),
        "intensity": intensity.spin.get_value() if intensity is not None else None,
        "intensity_sensitive": intensity is not None and intensity.is_sensitive(),
        "selected": parts.area.editor.selected,
        "stacked": layout is not None and layout.stacked,
        "scrolled": layout is not None and layout.scrolled,
        "ok": on_screen_rect(parts.dialog.get_widget_for_response(Gtk.ResponseType.OK)),
        "screen": [window.get_screen().get_width(), window.get_screen().get_height()],
    }


def label_texts():
    """The text of every label in the dialog."""
    found = []

    def walk(w):
        if isinstance(w, Gtk.Label):
            found.append(w.get_text())
        if isinstance(w, Gtk.Container):
            w.forall(walk)

    walk(parts.dialog)
    return found


def on_screen_rect(w):
    """``w``'s rectangle on the screen: [left, top, right, bottom]."""
    top = w.get_toplevel()
    x, y = w.translate_coordinates(top, 0, 0)
    _, ox, oy = top.get_window().get_origin()
    alloc = w.get_allocation()
    return [ox + x, oy + y, ox + x + alloc.width, oy + y + alloc.height]


def on_screen(w, x=None, y=None):
    """The screen point of ``w``'s point (x, y) (default: its centre)."""
    alloc = w.get_allocation()
    x = alloc.width / 2 if x is None else x
    y = alloc.height / 2 if y is None else y
    top = w.get_toplevel()
    tx, ty = w.translate_coordinates(top, int(x), int(y))
    _, ox, oy = top.get_window().get_origin()
    return str(ox + tx), str(oy + ty)


def xdotool(*args):
    subprocess.run(["xdotool", *args], check=True, capture_output=True, timeout=20)


def click(w, x=None, y=None):
    xdotool("mousemove", *on_screen(w, x, y), "click", "1")


def drag(w, start, end):
    xdotool("mousemove", *on_screen(w, *start), "mousedown", "1")
    xdotool("mousemove", *on_screen(w, (start[0] + end[0]) / 2, (start[1] + end[1]) / 2))
    xdotool("mousemove", *on_screen(w, *end), "mouseup", "1")


def button(text):
    """The dialog's first button whose label holds ``text``, the Reset popover's included (GTK keeps popovers among
    the window's internal children)."""
    found = []

    def walk(w):
        if isinstance(w, Gtk.Button) and text in (w.get_label() or ""):
            found.append(w)
        if isinstance(w, Gtk.Container):
            w.forall(walk)

    walk(parts.dialog)
    assert found, f"no button '{text}' in the dialog"
    return found[0]


def settled():
    """Steps that wait for the pointer events to arrive and for the preview to render what they changed."""
    yield 400
    yield lambda: not parts.preview._timer
    yield 300


def drag_first_light(dx, dy):
    """Drag the light map's first light by (dx, dy) pixels."""
    area = parts.area
    light = area.editor.lights.lights[0]
    start = (light.u * area.width, light.v * area.height)
    drag(area, start, (start[0] + dx, start[1] + dy))


def reset_to(item):
    """Steps: Reset, then its popover's item ``item`` (a part of its label); wait for the preview."""
    click(parts.dialog.get_widget_for_response(RESET))
    yield 500
    click(button(item))
    yield from settled()
    yield from settled()  # the camera read again where the horizon box changed


def reset():
    """Issue #41, defect 10: Reset restores every control."""
    yield from settled()
    record["initial"] = snapshot()
    drag_first_light(60, 20)
    yield from settled()
    record["dragged"] = snapshot()
    yield from reset_to("Initial")
    record["after_initial"] = snapshot()
    parts.presets.set_active([row[0] for row in parts.presets.get_model()].index("high-sun"))
    yield from settled()
    drag_first_light(-50, 10)
    click(widget("use-horizon"))
    yield from settled()
    click(parts.preview.widget, y=40)
    yield from settled()
    record["edited"] = snapshot()
    yield from reset_to("Factory")
    record["after_factory"] = snapshot()
    done(Gtk.ResponseType.CANCEL)


def layout():
    """Issue #41, defect 11: the dialog fits 1366 x 768, long messages wrap."""
    yield from settled()
    yield 500
    record["shown"] = snapshot()
    done(Gtk.ResponseType.CANCEL)


def lights():
    """Issue items b and c: with the sun preset, a click on empty sky adds a disk light of the sun's size; the
    selected light's intensity shows as a number, typed there it edits the light, and Shift+wheel shows in it."""
    yield from settled()
    record["initial"] = snapshot()
    parts.presets.set_active([row[0] for row in parts.presets.get_model()].index("sun"))
    yield from settled()
    area = parts.area
    click(area, 0.8 * area.width, 0.3 * area.height)  # empty sky, far from the sun
    yield from settled()
    record["added"] = snapshot()
    click(area.intensity_box.spin)
    xdotool("key", "ctrl+a")
    xdotool("type", "1.25")
    xdotool("key", "Tab")
    yield from settled()
    record["typed"] = snapshot()
    record["typed_setting"] = parts.config.get_property("light-map")
    xdotool("mousemove", *on_screen(area, 0.8 * area.width, 0.3 * area.height))
    xdotool("keydown", "shift", "click", "4", "keyup", "shift")  # Shift + wheel up: intensity + 0.1
    yield from settled()
    record["wheeled"] = snapshot()
    done(Gtk.ResponseType.CANCEL)


def selection():
    """Issue item a: with a selection left over, the dialog says it casts the selection (and its size), as the
    cutout the filter reads is."""
    yield from settled()
    record["shown"] = snapshot()
    record["cutout_source"] = parts.host.read_cutout(parts.host.pixel_plan()).source
    done(Gtk.ResponseType.OK)


def horizon_first():
    """Issue #41, defect 12: the fields take input only while the box is ticked; From guide; a click on the
    preview; then OK (the image keeps its camera)."""
    yield from settled()
    record["initial"] = snapshot()
    click(button("guide"))
    yield from settled()
    record["from_guide"] = snapshot()
    record["scale"] = parts.preview.scale
    click(parts.preview.widget, y=100)
    yield from settled()
    record["clicked"] = snapshot()
    click(widget("use-horizon"))
    yield from settled()
    yield from settled()
    record["unticked"] = snapshot()
    click(parts.preview.widget, y=228)
    yield from settled()
    record["clicked_again"] = snapshot()
    done(Gtk.ResponseType.OK)


def horizon_second():
    """Another image: nothing of the first image's horizon; From guide without a guide says how to add one."""
    yield from settled()
    record["initial"] = snapshot()
    click(button("guide"))
    yield 600
    record["from_guide"] = snapshot()
    done(Gtk.ResponseType.CANCEL)


def horizon_again():
    """The first image again, scaled by 2 since: its horizon, scaled with it."""
    yield from settled()
    record["initial"] = snapshot()
    done(Gtk.ResponseType.CANCEL)


def geometry_shown():
    """The lift and thickness: the arguments, the slider, From outline, the value shown and the note."""
    geometry = parts.geometry
    return {
        "lift": parts.config.get_property("lift"),
        "thickness": parts.config.get_property("thickness"),
        "slider": geometry.scale.get_value(),
        "from_outline": geometry.read.get_active(),
        "value": geometry.value.get_text(),
        "note": parts.preview.status.get_text(),
        "read": parts.preview.thickness_read,
        "bbox": parts.preview.bbox,
        "lift_row": parts.preview.lift_row,
        "scale": parts.preview.scale,
        "size": snapshot()["size"],
    }


def type_lift(text):
    spin = parts.geometry.lift.get_spin_button()
    click(spin)
    xdotool("key", "ctrl+a")
    xdotool("type", text)
    xdotool("key", "Tab")


def drag_ground(down):
    """Drag from just under the cutout's foot (the row its lift counts from) ``down`` preview rows further down, in
    the cutout's middle column."""
    bbox, scale = parts.preview.bbox, parts.preview.scale
    x, foot = (bbox[0] + bbox[2]) / 2 * scale, parts.preview.lift_row * scale
    drag(parts.preview.widget, (x, foot + 4), (x, foot + 4 + down))
    return foot + 4 + down  # the preview row the ground point was dragged to


def geometry():
    """The lift and thickness controls: a lift typed past 20 canvas heights is clamped with a note saying why; the
    preview's handle drags the ground point down (live); the slider sets the thickness; OK keeps both with the
    image."""
    yield from settled()
    yield from settled()  # the first render brings the thickness the outline reads as
    record["initial"] = geometry_shown()
    type_lift("99999")
    yield from settled()
    record["typed"] = geometry_shown()
    record["dragged_to"] = drag_ground(24)
    yield from settled()
    record["dragged"] = geometry_shown()
    parts.geometry.scale.set_value(1.0)  # round
    yield from settled()
    record["slid"] = geometry_shown()
    done(Gtk.ResponseType.OK)


def geometry_again():
    """The same image again: its lift and thickness as kept; a drag, then Reset to Initial Values brings them back,
    and Reset to Factory Defaults rests the object and reads the thickness from the outline."""
    yield from settled()
    yield from settled()
    record["initial"] = geometry_shown()
    drag_ground(10)
    yield from settled()
    record["dragged"] = geometry_shown()
    yield from reset_to("Initial")
    record["after_initial"] = geometry_shown()
    yield from reset_to("Factory")
    record["after_factory"] = geometry_shown()
    done(Gtk.ResponseType.CANCEL)


def geometry_other():
    """Another image: nothing of the first image's lift and thickness."""
    yield from settled()
    record["initial"] = geometry_shown()
    done(Gtk.ResponseType.CANCEL)


def done(response):
    with open(os.path.join(HERE, "out", "steps.jsonl"), "a") as f:
        f.write(json.dumps(record) + "\n")
    parts.dialog.response(response)


def drive(steps):
    """Run the generator ``steps`` on GTK's main loop: it yields a delay in ms or a condition to wait for."""

    def step(*_):
        try:
            wait = next(steps)
        except StopIteration:
            return False
        except Exception:  # noqa: BLE001 - report it and close the dialog, never hang GIMP
            record["error"] = traceback.format_exc()
            done(Gtk.ResponseType.CANCEL)
            return False
        if callable(wait):
            poll(wait, 100)
        else:
            GLib.timeout_add(wait, step)
        return False

    def poll(condition, left):  # every 100 ms, at most ``left`` times
        def check():
            if condition() or left <= 1:
                step()
            else:
                poll(condition, left - 1)
            return False

        GLib.timeout_add(100, check)

    GLib.idle_add(step)


RUNS = {
    "reset": reset,
    "layout": layout,
    "lights": lights,
    "selection": selection,
    "horizon-first": horizon_first,
    "horizon-second": horizon_second,
    "horizon-again": horizon_again,
    "geometry": geometry,
    "geometry-again": geometry_again,
    "geometry-other": geometry_other,
}
drive(RUNS[TASK["run"]]())
