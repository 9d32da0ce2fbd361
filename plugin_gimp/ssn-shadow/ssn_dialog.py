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
from gi.repository import Gdk, GdkPixbuf, Gimp, GimpUi, GLib, Gtk, Pango  # noqa: E402

from ssn_core import ShadowError, release, set_camera, settings_from_arguments, upload_cutout  # noqa: E402
from ssn_engine_link import camera_rules, light_editor, light_map, shadow_notes  # noqa: E402
from ssn_engine_link import client as engine_client  # noqa: E402
from ssn_gimp_host import config_values  # noqa: E402
from ssn_layout import Layout, choose_layout  # noqa: E402
from ssn_light_area import LightMapArea  # noqa: E402
from ssn_preview import PREVIEW_HEIGHT, PREVIEW_SIZE, render_preview  # noqa: E402
from ssn_progress import EngineWait  # noqa: E402
from ssn_settings import PROCEDURE_NAME, SettingsError, editor_light_map  # noqa: E402

CUSTOM = "(custom)"
SELFTEST_ENV = "SSN_SHADOW_DIALOG_SELFTEST"  # "1": the built-in self-test; a path to a .py: a test's script
SCREEN_SCREENSHOT_ENV = "SSN_SHADOW_SCREEN_SCREENSHOT"  # the selftest grabs the whole screen
PREVIEW_DELAY_MS = 150


class ShadowPreview:
    """A thumbnail of the image with the shadow multiplied on, re-rendered while the light moves."""

    def __init__(self, host, engine, on_camera_read=None, on_row_clicked=None) -> None:
        """``on_camera_read`` gets the editor's settings (:func:`camera_rules.camera_read_settings`) of each camera
        the model reads from the outline (the first analysis, and each one after the image's horizon is turned
        off); ``on_row_clicked`` the canvas row of a click on the preview. The image's cutout is uploaded once; a
        camera change sends the camera alone."""
        self.host, self.engine, self.on_camera_read = host, engine, on_camera_read
        self.on_row_clicked = on_row_clicked
        self.widget = Gtk.Image()
        self.clickable = Gtk.EventBox()  # exactly the picture's size, so event rows are thumbnail rows
        self.clickable.add(self.widget)
        self.clickable.set_halign(Gtk.Align.START)
        self.clickable.set_valign(Gtk.Align.START)
        self.clickable.set_tooltip_text("Click to put the image's horizon on that row")
        self.clickable.connect("button-press-event", self._on_press)
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
            cutout_id, read = upload_cutout(engine, host.read_cutout(host.pixel_plan()))
            self.cutout_id = cutout_id
            self._analysed(read)
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
                self._analysed(set_camera(self.engine, cutout_id, camera))
                self.camera = camera
            horizon = camera_rules.scaled_camera(camera, self.scale)["horizon"] if camera is not None else None
            rgb, no_shadow = render_preview(self.engine, cutout_id, settings, self.thumbnail, horizon)
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
        self.status.set_text(shadow_notes.no_shadow_note(no_shadow) if no_shadow else self._camera_note())

    def _analysed(self, camera_read: dict | None) -> None:
        self.camera_read = camera_read
        if camera_read is not None and self.on_camera_read is not None:
            self.on_camera_read(camera_rules.camera_read_settings(camera_read))

    def _on_press(self, _widget, event) -> bool:
        if event.button != 1 or event.type != Gdk.EventType.BUTTON_PRESS or self.cutout_id is None:
            return False
        if self.on_row_clicked is not None:
            self.on_row_clicked(camera_rules.row_from_preview(event.y, self.scale))
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

    preview = ShadowPreview(host, engine, show_camera_read, give_horizon)
    area: LightMapArea | None = None

    def keep_camera_read(*_) -> None:
        read = preview.camera_read
        show_camera_read(camera_rules.camera_read_settings(read) if read is not None else None)

    for name in ("use-horizon", "horizon", "fov"):
        config.connect(f"notify::{name}", keep_camera_read)

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
            dialog=dialog, config=config, host=host, preview=preview, area=area, presets=presets, layout=layout
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
