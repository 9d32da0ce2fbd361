"""The filter's dialog (GimpUi): preset, light-map editor, colour, opacity, AO strength and a live preview.

The colour, opacity and AO strength are the procedure's own arguments
(GimpUi.ProcedureDialog builds their widgets and remembers the last values);
the light map is edited in :class:`ssn_light_area.LightMapArea` and written
to the ``light-map`` argument as JSON when the user confirms.
"""

from __future__ import annotations

import os
import sys
from collections.abc import Iterator
from contextlib import contextmanager
from types import SimpleNamespace

import gi

gi.require_version("Gimp", "3.0")
gi.require_version("GimpUi", "3.0")
gi.require_version("Gtk", "3.0")
gi.require_version("GdkPixbuf", "2.0")
gi.require_version("Pango", "1.0")
from gi.repository import Gdk, GdkPixbuf, Gimp, GimpUi, GLib, GObject, Gtk, Pango  # noqa: E402

from ssn_core import ShadowError, release, send_cutout, set_camera, set_geometry, settings_from_arguments  # noqa: E402
from ssn_engine_link import camera_rules, geometry_clamp, light_editor, light_map, shadow_notes  # noqa: E402
from ssn_engine_link import client as engine_client  # noqa: E402
from ssn_gimp_host import config_values  # noqa: E402
from ssn_layout import Layout, choose_layout  # noqa: E402
from ssn_light_area import LightMapArea  # noqa: E402
from ssn_preview import (  # noqa: E402
    PREVIEW_HEIGHT,
    PREVIEW_SIZE,
    draw_ground_mark,
    in_lift_handle,
    lift_from_preview,
    render_preview,
)
from ssn_progress import EngineWait  # noqa: E402
from ssn_settings import (  # noqa: E402
    PROCEDURE_NAME,
    READ_THICKNESS,
    THICKNESS_SLIDER_TOP,
    SettingsError,
    clamp_thickness,
    editor_light_map,
    slider_from_thickness,
    thickness_from_slider,
    thickness_read_text,
)

CUSTOM = "(custom)"
SELFTEST_ENV = "SSN_SHADOW_DIALOG_SELFTEST"  # "1": the built-in self-test; a path to a .py: a test's script
SCREEN_SCREENSHOT_ENV = "SSN_SHADOW_SCREEN_SCREENSHOT"  # the selftest grabs the whole screen
PREVIEW_DELAY_MS = 150
DRAG_START = 3  # thumbnail pixels a press must move to be a drag (of the lift handle), not a click (the horizon)


class ShadowPreview:
    """A thumbnail of the image with the shadow multiplied on, re-rendered while the light moves."""

    def __init__(
        self, host, engine, on_camera_read=None, on_row_clicked=None, on_lift_dragged=None, on_thickness_read=None
    ) -> None:
        """``on_camera_read`` gets the editor's settings (:func:`camera_rules.camera_read_settings`) of each camera
        the model reads from the outline (the first analysis, and each one after the image's horizon is turned
        off); ``on_row_clicked`` the canvas row of a click on the preview; ``on_lift_dragged`` the lift (canvas
        rows) while the ground point under the cutout is dragged; ``on_thickness_read`` the thickness the outline
        reads as. The image's cutout is uploaded once; a camera or geometry change sends that alone."""
        self.host, self.engine, self.on_camera_read = host, engine, on_camera_read
        self.on_row_clicked, self.on_lift_dragged, self.on_thickness_read = (
            on_row_clicked,
            on_lift_dragged,
            on_thickness_read,
        )
        self.widget = Gtk.Image()
        self.clickable = Gtk.EventBox()  # exactly the picture's size, so event rows are thumbnail rows
        self.clickable.add(self.widget)
        self.clickable.set_halign(Gtk.Align.START)
        self.clickable.set_valign(Gtk.Align.START)
        self.clickable.set_tooltip_text(
            "Click to put the image's horizon on that row; drag the mark under the object down to lift it"
        )
        self.clickable.add_events(Gdk.EventMask.BUTTON_RELEASE_MASK | Gdk.EventMask.BUTTON1_MOTION_MASK)
        self.clickable.connect("button-press-event", self._on_press)
        self.clickable.connect("motion-notify-event", self._on_motion)
        self.clickable.connect("button-release-event", self._on_release)
        self._press: tuple[float, float, bool] | None = None  # a press being held: where, and on the lift handle
        self._dragged = False
        self.bbox: list[int] | None = None  # the cutout's bounds on the canvas (x0, y0, x1, y1)
        self.lift_row = 0  # the canvas row its lift counts from (its lowest pixel's, above a soft edge's rows)
        self.engine_geometry: tuple[float, float | None] = (0.0, None)  # the lift and thickness the worker has
        self.thickness_read: float | None = None  # what the outline reads as (the worker's set_geometry reply)
        self.geometry_note = ""  # why the dialog clamped the lift or thickness last, shown under the preview
        self.status = _wrap(Gtk.Label(xalign=0.0))
        self.scale = 1.0  # thumbnail pixels per image pixel
        self.cutout_id: str | None = None
        self.camera_read: dict | None = None  # the model's reading (image rows), or None
        self._values = None
        self._timer = False
        self.busy = False  # a render waits on the engine (the dialog's events are handled meanwhile)
        width, height = host.image.get_width(), host.image.get_height()
        self.image_height = height
        tw, th, _ = camera_rules.preview_size(width, height, PREVIEW_SIZE, PREVIEW_HEIGHT)
        try:
            self.thumbnail = host.thumbnail(tw, th)
            self.scale = self.thumbnail.width / width
            self.camera: dict | None = None  # the camera the worker's cutout was analysed with (image rows)
            reply = send_cutout(engine, host.read_cutout(host.pixel_plan()))
            self.cutout_id = str(reply["cutout"])
            bbox = reply.get("bbox")  # where a worker sends none, the preview has no lift handle
            self.bbox = [int(v) for v in bbox] if isinstance(bbox, list) and len(bbox) == 4 else None
            row = reply.get("lift_row")
            if self.bbox is not None:
                self.lift_row = int(row) if isinstance(row, int) and not isinstance(row, bool) else self.bbox[3] - 1
            self._analysed(reply.get("camera_read"))
        except (ShadowError, engine_client.EngineError) as exc:
            self.status.set_text(str(exc))

    def schedule(self, values_getter) -> None:
        """Render the latest values soon: at most one render per PREVIEW_DELAY_MS, so a light being dragged is
        followed live and a burst of edits renders once."""
        if self.cutout_id is None:
            return
        self._values = values_getter
        if self._timer:
            return
        self._timer = True

        def fire() -> bool:
            if self.busy:
                return True  # the render before is still waiting on the engine: try again after it
            self._timer = False
            if self._values is not None:
                self.render(self._values())
            return False

        GLib.timeout_add(PREVIEW_DELAY_MS, fire)

    def render(self, values: dict) -> None:
        if self.cutout_id is None or self.busy:
            return
        with self.engine_turn():
            self._render(self.cutout_id, values)

    @contextmanager
    def engine_turn(self) -> Iterator[None]:
        """Mark the preview busy while the dialog waits on the engine. The dialog's events are handled during
        the wait, so a preview timer firing then must wait for its turn: the client answers one request at a time,
        and a second one from this thread would wait for the first forever."""
        self.busy = True
        try:
            yield
        finally:
            self.busy = False
            if isinstance(self.engine.on_wait, EngineWait):
                self.engine.on_wait.reset()

    def _render(self, cutout_id: str, values: dict) -> None:
        try:
            settings = settings_from_arguments(values)
            camera = settings.camera()
            if camera != self.camera:  # a new horizon: the worker analyses the cutout again
                if self.engine_geometry[0] > 0:  # rest the object first: the new horizon may not take the lift
                    self._set_geometry(cutout_id, 0.0, self.engine_geometry[1])
                self._analysed(set_camera(self.engine, cutout_id, camera))
                self.camera = camera
            geometry = (settings.lift, settings.thickness)
            if geometry != self.engine_geometry:
                self._set_geometry(cutout_id, *geometry)
            horizon = camera_rules.scaled_camera(camera, self.scale)["horizon"] if camera is not None else None
            rgb, no_shadow = render_preview(self.engine, cutout_id, settings, self.thumbnail, horizon)
            if self.thickness_read is None:  # the reading, for the Thickness row: asked after the first picture
                self._set_geometry(cutout_id, *self.engine_geometry)
            if self.bbox is not None:
                size = (self.thumbnail.width, self.thumbnail.height)
                rgb = draw_ground_mark(rgb, size, self.scale, self.bbox, self.lift_row, settings.lift)
        except engine_client.Cancelled as exc:  # the dialog closed while the engine worked: it was stopped
            self.cutout_id = None
            self.status.set_text(str(exc))
            return
        except (ShadowError, SettingsError) as exc:
            self.status.set_text(str(exc))
            return
        w, h = self.thumbnail.width, self.thumbnail.height
        self.widget.set_from_pixbuf(
            GdkPixbuf.Pixbuf.new_from_bytes(GLib.Bytes.new(rgb), GdkPixbuf.Colorspace.RGB, False, 8, w, h, 3 * w)
        )
        note = shadow_notes.no_shadow_note(no_shadow) if no_shadow else self._camera_note()
        self.status.set_text("\n".join(text for text in (self.geometry_note, note) if text))

    def _set_geometry(self, cutout_id: str, lift: float, thickness: float | None) -> None:
        """Give the worker's cutout this lift and thickness (a refusal: :class:`ShadowError`, the cutout keeping
        its geometry) and pass on the thickness the outline reads as."""
        reply = set_geometry(self.engine, cutout_id, lift, thickness)
        self.engine_geometry = (lift, thickness)
        read = reply.get("thickness_read")
        self.thickness_read = float(read) if isinstance(read, (int, float)) else None
        if self.on_thickness_read is not None:
            self.on_thickness_read(self.thickness_read)

    def horizon_in_use(self, values: dict) -> float | None:
        """The horizon row (canvas) of the camera the engine uses for ``values``: the image's where it is given,
        else the one the model read from the outline; None where neither is known."""
        if values.get("use-horizon"):
            return float(values["horizon"])
        return None if self.camera_read is None else float(self.camera_read["horizon"])

    def _analysed(self, camera_read: dict | None) -> None:
        self.camera_read = camera_read
        if camera_read is not None and self.on_camera_read is not None:
            self.on_camera_read(camera_rules.camera_read_settings(camera_read))

    def _on_press(self, _widget, event) -> bool:
        """A press starts a click (on release: the horizon on that row) or, under the cutout, a drag of its ground
        point (the lift)."""
        if event.button != 1 or event.type != Gdk.EventType.BUTTON_PRESS or self.cutout_id is None:
            return False
        handle = self.bbox is not None and in_lift_handle(event.x, event.y, self.scale, self.bbox, self.lift_row)
        self._press, self._dragged = (event.x, event.y, handle), False
        return True

    def _on_motion(self, _widget, event) -> bool:
        """Dragging the ground point: the lift follows the pointer's row, live (canvas rows = preview rows /
        scale)."""
        if self._press is None or not self._press[2] or self.bbox is None:
            return False
        if not self._dragged and abs(event.y - self._press[1]) < DRAG_START:
            return True
        self._dragged = True
        if self.on_lift_dragged is not None:
            self.on_lift_dragged(lift_from_preview(event.y, self.scale, self.lift_row))
        return True

    def _on_release(self, _widget, event) -> bool:
        if event.button != 1 or self._press is None:
            return False
        press, dragged = self._press, self._dragged
        self._press, self._dragged = None, False
        if not dragged and self.on_row_clicked is not None:
            self.on_row_clicked(camera_rules.row_from_preview(press[1], self.scale))
        return True

    def _camera_note(self) -> str:
        return "" if self.camera_read is None else camera_rules.camera_read_note(self.camera_read, self.image_height)

    def close(self) -> None:
        if self.cutout_id is not None:
            release(self.engine, self.cutout_id)


def run_dialog(procedure: Gimp.Procedure, config: Gimp.ProcedureConfig, host, engine) -> bool:
    """Show the dialog; on OK store the edited light map in ``config`` and return True."""
    GimpUi.init(PROCEDURE_NAME)
    dialog = GimpUi.ProcedureDialog(procedure=procedure, config=config, title="Soft Shadow (SSN)")
    for name in ("opacity", "ao-strength", "fov"):  # GIMP's slider-with-entry widgets, not bare spin buttons
        dialog.get_spin_scale(name, 1.0)
    fields = dialog.fill_box(  # packed under the light map below
        "ssn-fields", ["shadow-color", "opacity", "ao-strength", "use-horizon", "horizon", "fov", "keep-whole-shadow"]
    )
    for name in ("horizon", "fov"):  # they do nothing while the image's horizon is not given
        dialog.set_sensitive(name, True, config, "use-horizon", False)

    def values() -> dict:
        out = config_values(config)
        out["light-map"] = editor.to_json()
        return out

    try:
        lights = editor_light_map(config.get_property("light-map"))
    except SettingsError:
        lights = light_map.preset(light_map.DEFAULT_PRESET)

    def show_camera_read(read: dict | None) -> None:
        # While the image's horizon is not given, the camera fields show the camera the model read (the note under
        # the preview names it), also after a Reset; ticking the box starts from that reading.
        if read is None or config.get_property("use-horizon"):
            return
        for name, value in read.items():
            if config.get_property(name) != value:
                config.set_property(name, value)

    def give_horizon(row: float) -> None:
        config.set_property("use-horizon", True)  # first: unticked, the fields keep the camera read
        config.set_property("horizon", row)

    geometry = GeometryRow(dialog, config)
    preview = ShadowPreview(host, engine, show_camera_read, give_horizon, geometry.drag_lift, geometry.show_read)
    geometry.preview = preview
    area: LightMapArea | None = None

    def keep_camera_read(*_) -> None:
        read = preview.camera_read
        show_camera_read(camera_rules.camera_read_settings(read) if read is not None else None)

    for name in ("use-horizon", "horizon", "fov"):
        config.connect(f"notify::{name}", keep_camera_read)
    for name in ("lift", "use-horizon", "horizon"):  # a lift the camera in use does not take is clamped
        config.connect(f"notify::{name}", geometry.check_lift)
    config.connect("notify::thickness", geometry.check_thickness)
    geometry.check_lift()

    def on_change(live: bool, new_stroke: bool) -> None:
        if area is not None:
            area.refresh()
        if not live and not syncing[0]:
            if presets.get_active_text() != CUSTOM:
                presets.set_active(len(light_map.PRESETS))
            store_light_map()
        preview.schedule(values)

    def on_select(index: int | None) -> None:
        if area is not None:
            area.refresh()

    editor = light_editor.LightMapEditor(lights, on_change, on_select)
    syncing = [False]  # the editor, the preset box and the light-map setting are being made to agree

    @contextmanager
    def in_sync():
        before, syncing[0] = syncing[0], True
        try:
            yield
        finally:
            syncing[0] = before

    def light_map_argument() -> str:
        name = presets.get_active_text()
        return name if name in light_map.PRESETS else editor.to_json()

    def store_light_map() -> None:
        # The setting follows every complete edit, so that Reset (to initial values or to factory defaults) finds
        # a setting to change back and the map follows it (on_light_map_setting).
        with in_sync():
            config.set_property("light-map", light_map_argument())

    presets = Gtk.ComboBoxText()
    for name in light_map.PRESETS:
        presets.append_text(name)
    presets.append_text(CUSTOM)
    current = config.get_property("light-map").strip()
    names = list(light_map.PRESETS)
    presets.set_active(names.index(current) if current in names else len(names))

    def on_preset(combo) -> None:
        name = combo.get_active_text()
        if name in light_map.PRESETS and not syncing[0]:
            with in_sync():
                editor.load(light_map.preset(name))
            store_light_map()

    presets.connect("changed", on_preset)

    def on_light_map_setting(*_) -> None:
        # Reset, Load Saved Settings (or a script) set the argument: show that light map, and its preset's name.
        if syncing[0]:
            return
        text = config.get_property("light-map").strip()
        try:
            loaded = editor_light_map(text)
        except SettingsError:
            return
        with in_sync():
            presets.set_active(names.index(text) if text in names else len(names))
            editor.load(loaded)

    config.connect("notify::light-map", on_light_map_setting)
    area = LightMapArea(editor)

    # The light map (the main control) above colour, opacity, AO and camera, beside the preview: the dialog then
    # fits a 1366 x 768 screen (stacked, it was 814 px tall; with the fields under both, 774 for a portrait image).
    # On a narrow screen (768 x 1366) the preview goes under the light map instead (_fit_to_screen).
    lights_box = Gtk.Box(orientation=Gtk.Orientation.VERTICAL, spacing=6)
    row = Gtk.Box(spacing=6)
    row.pack_start(Gtk.Label(label="Preset:"), False, False, 0)
    row.pack_start(presets, True, True, 0)
    row.pack_start(area.size_box, False, False, 0)  # the selected light's size, beside the preset: no taller
    lights_box.pack_start(row, False, False, 0)
    row = Gtk.Box(spacing=6)  # and its intensity, under the size (beside it, the dialog was 965 px wide)
    row.pack_end(area.intensity_box, False, False, 0)
    lights_box.pack_start(row, False, False, 0)
    lights_box.pack_start(_axes(area), False, False, 0)
    lights_box.pack_start(
        _wrap(
            Gtk.Label(
                label="Light map: click to add a light, drag to move it, wheel: size, Shift+wheel: intensity, "
                "right-click: remove",
                xalign=0.0,
            )
        ),
        False,
        False,
        0,
    )
    lights_box.pack_start(fields, False, False, 0)
    guide = Gtk.Button.new_with_mnemonic("From _guide")
    guide.set_tooltip_text("Put the image's horizon on its first horizontal guide")

    def on_guide(_button) -> None:
        guide_row = camera_rules.horizon_from_guides(host.horizontal_guides())
        if guide_row is None:
            preview.status.set_text(camera_rules.NO_GUIDE)
        else:
            give_horizon(guide_row)

    guide.connect("clicked", on_guide)
    title = Gtk.Box(spacing=6)
    title.pack_start(Gtk.Label(label="Preview: click to set the horizon", xalign=0.0), True, True, 0)
    title.pack_end(guide, False, False, 0)
    preview_box = Gtk.Box(orientation=Gtk.Orientation.VERTICAL, spacing=6)
    preview_box.pack_start(_wrap(Gtk.Label(label=host.target_note(), xalign=0.0)), False, False, 0)
    preview_box.pack_start(title, False, False, 0)
    preview_box.pack_start(preview.clickable, False, False, 0)
    preview_box.pack_start(preview.status, False, False, 0)
    preview_box.pack_start(geometry.widget, False, False, 0)
    box = Gtk.Box(spacing=12)
    box.pack_start(lights_box, False, False, 0)
    box.pack_start(preview_box, True, True, 0)
    content = dialog.get_content_area()
    content.pack_start(box, True, True, 6)
    content.reorder_child(box, 0)  # above GIMP's Load Saved Settings and Save Settings
    config.connect("notify", lambda *_: preview.schedule(values))
    box.show_all()
    layout = _fit_to_screen(dialog, box)
    waiting = engine.on_wait if isinstance(engine.on_wait, EngineWait) else None
    if waiting is not None:  # a frozen worker leaves the dialog working, and closing it stops the wait
        waiting.handle_events = _handle_events
        dialog.connect("response", lambda *_: waiting.cancel() if preview.busy else None)
    preview.schedule(values)

    selftest = os.environ.get(SELFTEST_ENV, "")
    if selftest == "1":
        GLib.timeout_add(300, _selftest, dialog, area, preview, values, config)
    elif selftest.endswith(".py"):
        parts = SimpleNamespace(
            dialog=dialog,
            config=config,
            host=host,
            preview=preview,
            area=area,
            presets=presets,
            layout=layout,
            geometry=geometry,
        )
        GLib.timeout_add(300, _run_test_script, selftest, parts)
    try:
        ok = dialog.run()
        if ok:
            store_light_map()
        return ok
    finally:
        if waiting is not None:
            waiting.handle_events = None
        preview.close()
        dialog.destroy()


class GeometryRow:
    """The artist's geometry under the preview, one compact row each: **Lift** (a number of canvas pixels, GIMP's
    widget of the ``lift`` argument; the preview's handle drags it) and **Thickness** (a slider, flat - round -
    deep, with *From outline* and the value the outline reads as), both the procedure's arguments, so that Reset
    and GIMP's saved settings reach them. A value the engine would refuse is clamped, and the line under the
    preview says why (:func:`geometry_clamp.clamp_lift`, :func:`ssn_settings.clamp_thickness`)."""

    def __init__(self, dialog, config) -> None:
        self.config = config
        self.preview: ShadowPreview | None = None
        self._syncing = False
        self._checked: float | None = None  # the lift last checked: a notify that changes nothing keeps the note
        self.lift = dialog.get_widget("lift", GObject.TYPE_NONE)  # GimpLabelSpin, bound to the argument
        self.lift.set_tooltip_text(
            "Canvas pixels from the object's lowest point down to the ground beneath it (0: it rests on the "
            "ground). Or drag the mark under the object in the preview down."
        )
        self.read = Gtk.CheckButton.new_with_mnemonic("Fro_m outline")
        self.read.set_tooltip_text("Use the thickness the cutout's outline reads as")
        self.scale = Gtk.Scale.new_with_range(Gtk.Orientation.HORIZONTAL, 0.0, THICKNESS_SLIDER_TOP, 0.01)
        self.scale.set_draw_value(False)
        self.scale.set_size_request(140, -1)
        for position, text in ((0.0, "flat"), (1.0, "round"), (THICKNESS_SLIDER_TOP, "deep")):
            self.scale.add_mark(position, Gtk.PositionType.BOTTOM, f"<small>{text}</small>")
        self.scale.set_tooltip_text(
            "The object's depth along the view over its width: 0 a flat sign, 1 a ball, about 2 a person seen from "
            "the side, 8 a rod seen end-on"
        )
        self.value = Gtk.Label(xalign=0.0)  # "read 0.29", or "0.50 (read 0.29)"
        label = Gtk.Label.new_with_mnemonic("_Thickness")
        label.set_mnemonic_widget(self.scale)
        lift_row = Gtk.Box(spacing=6)  # Lift [number] px    Thickness read 0.29
        lift_row.pack_start(self.lift, False, False, 0)
        lift_row.pack_start(Gtk.Label(label="px"), False, False, 0)
        lift_row.pack_start(label, False, False, 12)
        lift_row.pack_start(self.value, False, False, 0)
        thickness_row = Gtk.Box(spacing=6)  # flat - round - deep [slider]    [x] From outline
        thickness_row.pack_start(self.scale, True, True, 0)
        thickness_row.pack_start(self.read, False, False, 0)
        self.widget = Gtk.Box(orientation=Gtk.Orientation.VERTICAL, spacing=2)
        self.widget.pack_start(lift_row, False, False, 0)
        self.widget.pack_start(thickness_row, False, False, 0)
        self.scale.connect("value-changed", self._on_slider)
        self.read.connect("toggled", self._on_read_toggled)
        self.check_thickness()

    def _set(self, name: str, value: float) -> None:
        if self.config.get_property(name) != value:
            self.config.set_property(name, value)

    def _note(self, why: str) -> None:
        if self.preview is not None:
            self.preview.geometry_note = why

    def drag_lift(self, lift: float) -> None:
        """The preview's handle dragged to ``lift`` canvas rows."""
        self._set("lift", lift)

    def check_lift(self, *_) -> None:
        """Clamp the lift to what the engine takes for this canvas and the camera in use, and say why."""
        if self._syncing or self.preview is None:
            return
        preview = self.preview
        lift = self.config.get_property("lift")
        lowest = preview.lift_row if preview.bbox is not None else None
        values = {name: self.config.get_property(name) for name in ("use-horizon", "horizon")}
        clamped, why = geometry_clamp.clamp_lift(lift, preview.image_height, lowest, preview.horizon_in_use(values))
        if clamped != lift:
            self._syncing = True
            try:
                self._set("lift", clamped)
            finally:
                self._syncing = False
        if why or lift != self._checked:
            self._note(why)
        self._checked = clamped

    def check_thickness(self, *_) -> None:
        """Clamp the thickness (a script's or a saved value) and show it: the slider, *From outline*, the value."""
        if self._syncing:
            return
        thickness = self.config.get_property("thickness")
        clamped, why = clamp_thickness(thickness)
        self._syncing = True
        try:
            self._set("thickness", clamped)
            read = self.preview.thickness_read if self.preview is not None else None
            reading = clamped < 0
            self.read.set_active(reading)
            shown = (read if read is not None else 0.0) if reading else clamped
            self.scale.set_value(slider_from_thickness(shown))
            self.value.set_text(
                thickness_read_text(read) if reading else f"{clamped:.2f} ({thickness_read_text(read)})"
            )
        finally:
            self._syncing = False
        if why:
            self._note(why)

    def show_read(self, read: float | None) -> None:
        """The thickness the outline reads as, from the engine."""
        self.check_thickness()

    def _on_slider(self, scale) -> None:
        if not self._syncing:
            self._set("thickness", thickness_from_slider(scale.get_value()))

    def _on_read_toggled(self, button) -> None:
        if self._syncing:
            return
        if button.get_active():
            self._set("thickness", READ_THICKNESS)
        else:  # start from the reading
            read = self.preview.thickness_read if self.preview is not None else None
            self._set("thickness", round(read, 2) if read is not None else 1.0)


def _fit_to_screen(dialog: Gtk.Dialog, box: Gtk.Box) -> Layout:
    """Lay the dialog's two columns (``box``) out for the screen's work area (:func:`ssn_layout.choose_layout`):
    side by side, or stacked (the preview under the light map) where the screen is too narrow for that, or
    scrolled where even that does not fit. Returns the layout chosen."""
    side = dialog.get_preferred_size()[1]
    box.set_orientation(Gtk.Orientation.VERTICAL)
    stacked = dialog.get_preferred_size()[1]
    area = _work_area(dialog)
    layout = choose_layout((side.width, side.height), (stacked.width, stacked.height), area)
    if not layout.stacked:
        box.set_orientation(Gtk.Orientation.HORIZONTAL)
    if layout.scrolled:
        whole, inner = dialog.get_preferred_size()[1], box.get_preferred_size()[1]
        content = dialog.get_content_area()
        content.remove(box)
        scrolled = Gtk.ScrolledWindow()
        scrolled.set_policy(Gtk.PolicyType.AUTOMATIC, Gtk.PolicyType.AUTOMATIC)
        scrolled.set_propagate_natural_width(True)
        scrolled.set_propagate_natural_height(True)
        scrolled.set_max_content_width(max(100, layout.max_width - (whole.width - inner.width)))
        scrolled.set_max_content_height(max(100, layout.max_height - (whole.height - inner.height)))
        scrolled.add(box)
        content.pack_start(scrolled, True, True, 6)
        content.reorder_child(scrolled, 0)
        scrolled.show_all()
    return layout


def _work_area(dialog: Gtk.Dialog) -> tuple[int, int]:
    """The width and height of the work area (the monitor less its panels) of the screen the dialog opens on."""
    display = dialog.get_display()
    monitor = display.get_primary_monitor() or display.get_monitor(0)
    if monitor is None:  # no monitor known: as large as the screen
        screen = dialog.get_screen()
        return screen.get_width(), screen.get_height()
    rect = monitor.get_workarea()
    return rect.width, rect.height


def _handle_events() -> None:
    """Handle the dialog's pending events (while a preview waits on the engine)."""
    while Gtk.events_pending():
        Gtk.main_iteration_do(False)


def _axes(area: Gtk.Widget) -> Gtk.Widget:
    """The light map with its axes labelled: where a light there sits, and where its shadow falls."""

    def small(text: str, xalign: float = 0.5) -> Gtk.Label:
        label = Gtk.Label(xalign=xalign)
        label.set_markup(f"<small>{text}</small>")
        return label

    top = Gtk.Box(spacing=0)
    top.pack_start(small("behind you", 0.0), True, True, 0)
    top.pack_start(small("behind the object: shadow towards you"), True, True, 0)
    top.pack_start(small("behind you", 1.0), True, True, 0)
    side = Gtk.Box(orientation=Gtk.Orientation.VERTICAL)
    side.pack_start(small("zenith", 1.0), False, False, 0)
    side.pack_end(small("horizon", 1.0), False, False, 0)
    grid = Gtk.Grid(column_spacing=4, row_spacing=2)  # the top labels span the map's width, not the dialog's
    grid.attach(top, 1, 0, 1, 1)
    grid.attach(side, 0, 1, 1, 1)
    grid.attach(area, 1, 1, 1, 1)
    grid.attach(
        _wrap(small("a light right of centre casts its shadow to the left, and a low light a long one", 0.0)),
        0,
        2,
        2,
        1,
    )
    return grid


def _wrap(label: Gtk.Label) -> Gtk.Label:
    """``label``, wrapping its lines (a long word too) instead of widening the dialog."""
    label.set_line_wrap(True)
    label.set_line_wrap_mode(Pango.WrapMode.WORD_CHAR)
    label.set_max_width_chars(48)
    return label


def _run_test_script(path: str, parts: SimpleNamespace) -> bool:
    """For the integration tests (SSN_SHADOW_DIALOG_SELFTEST=<script.py>): run the test's script with the dialog's
    parts (``parts``: dialog, config, host, preview, area, presets and the ``layout`` chosen); the script presses OK
    or Cancel itself."""
    with open(path, encoding="utf-8") as script:
        exec(compile(script.read(), path, "exec"), {"__file__": path, "parts": parts})  # noqa: S102 - a test's own
    return False


def _selftest(dialog, area: LightMapArea, preview: ShadowPreview, values, config) -> bool:
    """For the integration test (SSN_SHADOW_DIALOG_SELFTEST=1): add and drag a light through the
    widget's event handlers, resize it, render the preview, set the light-map setting as Reset to Factory
    Defaults does (the map must follow), then put the edited map back and press OK.

    With SSN_SHADOW_DIALOG_SCREENSHOT=<path.png> it also saves a picture of the dialog. With
    SSN_SHADOW_SCREEN_SCREENSHOT=<path.png> it saves one of the whole screen instead (tools/gimp_window_figure.py):
    the horizon option on with a row inside the image, the preview rendered with it, and the dialog moved to the
    screen's top-right corner (Xvfb has no window manager to place it) so that the image window shows beside it.
    """
    from types import SimpleNamespace

    from gi.repository import Gdk

    if preview.busy:  # called among the events handled while a preview waits on the engine: start after it
        return True
    editor = area.editor
    x, y = 0.85 * area.width, 0.7 * area.height
    press = SimpleNamespace(x=x, y=y, button=1, type=Gdk.EventType.BUTTON_PRESS, state=0)
    area._on_press(area, press)
    moved = SimpleNamespace(x=x - 0.05 * area.width, y=y + 0.02 * area.height, state=Gdk.ModifierType.BUTTON1_MASK)
    area._on_motion(area, moved)
    area._on_release(area, SimpleNamespace(button=1))
    editor.scroll(1)
    assert editor.selected is not None
    light = editor.lights.lights[editor.selected]
    print(f"ssn-shadow dialog selftest: light at u={light.u:.3f} v={light.v:.3f}", file=sys.stderr, flush=True)
    _size_selftest(area, preview, values)
    preview.render(values())
    pixbuf = preview.widget.get_pixbuf()
    size = f"{pixbuf.get_width()}x{pixbuf.get_height()}" if pixbuf is not None else "none"
    print(
        f"ssn-shadow dialog selftest: lights={len(editor.lights)} preview={size} status={preview.status.get_text()!r}",
        file=sys.stderr,
        flush=True,
    )
    print(
        f"ssn-shadow dialog selftest: horizon setting {config.get_property('horizon'):.0f}, "
        f"field of view {config.get_property('fov'):.0f}, on: {config.get_property('use-horizon')}",
        file=sys.stderr,
        flush=True,
    )
    edited = editor.to_json()
    config.set_property("light-map", "high-sun")  # what Reset to Factory Defaults / Load Saved Settings do
    shown = editor.lights.to_dict() == light_map.preset("high-sun").to_dict()
    print(
        f"ssn-shadow dialog selftest: after a settings reset the map shows high-sun: {shown}",
        file=sys.stderr,
        flush=True,
    )
    config.set_property("light-map", edited)

    def finish() -> bool:
        if preview.busy:  # a preview of the edits above waits on the engine: press OK once it is shown
            return True
        window = dialog.get_window()
        print(
            f"ssn-shadow dialog selftest: dialog {window.get_width()}x{window.get_height()}",
            file=sys.stderr,
            flush=True,
        )
        path = os.environ.get("SSN_SHADOW_DIALOG_SCREENSHOT")
        if path:
            shot = Gdk.pixbuf_get_from_window(window, 0, 0, window.get_width(), window.get_height())
            shot.savev(path, "png", [], [])
        if os.environ.get(SCREEN_SCREENSHOT_ENV):
            _show_horizon(preview, values, config)
            _to_top_right(dialog)
            GLib.timeout_add(1500, grab_screen)  # time to draw the preview and the moved dialog
            return False
        dialog.response(Gtk.ResponseType.OK)
        return False

    def grab_screen() -> bool:
        root = Gdk.get_default_root_window()
        shot = Gdk.pixbuf_get_from_window(root, 0, 0, root.get_width(), root.get_height())
        shot.savev(os.environ[SCREEN_SCREENSHOT_ENV], "png", [], [])
        window = dialog.get_window()
        print(
            f"ssn-shadow dialog selftest: screen {root.get_width()}x{root.get_height()}, dialog at "
            f"{window.get_origin()[1:]} {window.get_width()}x{window.get_height()}",
            file=sys.stderr,
            flush=True,
        )
        dialog.response(Gtk.ResponseType.OK)
        return False

    GLib.timeout_add(400, finish)
    return False


def _size_selftest(area: LightMapArea, preview: ShadowPreview, values) -> None:
    """For the integration test: set the selected light's size in the Size box to 30 (a broad light, the
    network's) and then 0.53 degrees, render the preview at each and print the light's angle and how crisp its
    shadow is alone (:func:`_crispness`)."""
    editor, crisp = area.editor, {}
    assert editor.selected is not None and preview.cutout_id is not None
    for degrees in (30.0, 0.53):
        area.size_box.spin.set_value(degrees)
        preview.render(values())
        alone = dict(values(), **{"light-map": light_map.LightMap([editor.lights.lights[editor.selected]]).to_json()})
        crisp[degrees] = _crispness(preview, preview.cutout_id, alone)
    light = editor.lights.lights[editor.selected]
    print(
        f"ssn-shadow dialog selftest: size box {area.size_box.spin.get_value():.2f}, light angle {light.angle}, "
        f"shadow crispness at 30 degrees {crisp[30.0]:.4f}, at 0.53 degrees {crisp[0.53]:.4f}",
        file=sys.stderr,
        flush=True,
    )


def _crispness(preview: ShadowPreview, cutout_id: str, values: dict) -> float:
    """The shadow's gradient energy per unit of darkness in a preview of ``values`` (no horizon line drawn): the
    sum of squared steps between neighbouring pixels of its darkness (the thumbnail's red channel less the
    preview's) over the darkness's sum."""
    thumb = preview.thumbnail
    w, h = thumb.width, thumb.height
    settings = settings_from_arguments(values)
    with preview.engine_turn():
        shown, _ = render_preview(preview.engine, cutout_id, settings, thumb, horizon=-float(h))  # off the image
    dark = [[thumb.data[(y * w + x) * thumb.channels] - shown[3 * (y * w + x)] for x in range(w)] for y in range(h)]
    energy = sum((row[x + 1] - row[x]) ** 2 for row in dark for x in range(w - 1))
    energy += sum((dark[y + 1][x] - dark[y][x]) ** 2 for y in range(h - 1) for x in range(w))
    return energy / max(1, sum(max(0, d) for row in dark for d in row))


def _show_horizon(preview: ShadowPreview, values, config) -> None:
    """Turn the horizon option on, with the row at 35 % of the image height unless it already lies inside the
    image, and render the preview with it (the preview draws the horizon line)."""
    height = preview.host.image.get_height()
    config.set_property("use-horizon", True)
    if not 0.05 * height < config.get_property("horizon") < 0.95 * height:
        config.set_property("horizon", float(round(0.35 * height)))
    preview.render(values())


def _to_top_right(dialog) -> None:
    """Move the dialog to the screen's top-right corner."""
    from gi.repository import Gdk

    screen_width = Gdk.get_default_root_window().get_width()
    dialog.move(max(0, screen_width - dialog.get_window().get_width()), 0)
