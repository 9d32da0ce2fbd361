"""The light-map editor widget (GTK 3): shows the map and forwards pointer gestures to LightMapEditor.

The editor, the map picture and the light markers are the host kit's (the
same as Krita's); the widget is a Gtk.Image in a Gtk.EventBox, so it needs no
pycairo (GIMP's Python does not ship it). Its Size box (:class:`LightSizeBox`)
shows and sets the selected light's size in degrees, its Intensity box
(:class:`LightIntensityBox`) the selected light's intensity.
"""

from __future__ import annotations

import gi

gi.require_version("Gtk", "3.0")
gi.require_version("Gdk", "3.0")
gi.require_version("GdkPixbuf", "2.0")
from gi.repository import Gdk, GdkPixbuf, GLib, Gtk  # noqa: E402

from ssn_engine_link import light_editor, light_map, light_map_picture, light_size  # noqa: E402

MAP_WIDTH = 384  # the map is 2:1


class LightMapArea(Gtk.EventBox):
    """Click to add a light, drag to move, wheel to resize (Shift: intensity), right-click/Delete to remove."""

    def __init__(self, editor: light_editor.LightMapEditor) -> None:
        super().__init__()
        self.editor = editor
        self.width, self.height = MAP_WIDTH, MAP_WIDTH // 2
        self.image = Gtk.Image()
        self.add(self.image)
        self.size_box = LightSizeBox(editor)
        self.intensity_box = LightIntensityBox(editor)
        # exactly the picture's size, so event coordinates are picture coordinates
        self.set_halign(Gtk.Align.CENTER)
        self.set_valign(Gtk.Align.CENTER)
        self.set_can_focus(True)
        self.add_events(
            Gdk.EventMask.BUTTON_PRESS_MASK
            | Gdk.EventMask.BUTTON_RELEASE_MASK
            | Gdk.EventMask.POINTER_MOTION_MASK
            | Gdk.EventMask.SCROLL_MASK
            | Gdk.EventMask.SMOOTH_SCROLL_MASK
            | Gdk.EventMask.KEY_PRESS_MASK
        )
        self.connect("button-press-event", self._on_press)
        self.connect("button-release-event", self._on_release)
        self.connect("motion-notify-event", self._on_motion)
        self.connect("scroll-event", self._on_scroll)
        self.connect("key-press-event", self._on_key)
        self.set_tooltip_text(
            "Sky seen from the object: centre = behind the object (shadow towards you), "
            "edges = behind the camera; top = zenith, bottom = horizon.\n"
            "Click: add a light · drag: move · wheel: size · Shift+wheel: intensity · "
            "right-click or Delete: remove"
        )
        self.refresh()

    def _uv(self, event) -> tuple[float, float]:
        return event.x / self.width, min(max(event.y / self.height, 0.0), 1.0)

    def refresh(self) -> None:
        """Redraw the map and the markers."""
        w, h = light_map_picture.PICTURE_SIZE
        picture = GdkPixbuf.Pixbuf.new_from_bytes(
            GLib.Bytes.new(light_map_picture.map_rgb(self.editor.lights, w, h)),
            GdkPixbuf.Colorspace.RGB,
            False,
            8,
            w,
            h,
            3 * w,
        ).scale_simple(self.width, self.height, GdkPixbuf.InterpType.BILINEAR)
        stride, data = picture.get_rowstride(), picture.get_pixels()
        rgb = bytearray(b"".join(data[y * stride : y * stride + 3 * self.width] for y in range(self.height)))
        light_map_picture.overlay_markers(rgb, self.width, self.height, self.editor.lights, self.editor.selected)
        pixbuf = GdkPixbuf.Pixbuf.new_from_bytes(
            GLib.Bytes.new(bytes(rgb)), GdkPixbuf.Colorspace.RGB, False, 8, self.width, self.height, 3 * self.width
        )
        self.image.set_from_pixbuf(pixbuf)
        self.size_box.show_selected()
        self.intensity_box.show_selected()

    def _on_press(self, _widget, event) -> bool:
        self.grab_focus()
        if event.type != Gdk.EventType.BUTTON_PRESS:
            return True  # ignore the extra double/triple-click events
        u, v = self._uv(event)
        if event.button == 1:
            self.editor.press(u, v)
        elif event.button == 3:
            self.editor.remove_at(u, v)
        return True

    def _on_motion(self, _widget, event) -> bool:
        if event.state & Gdk.ModifierType.BUTTON1_MASK:
            self.editor.drag(*self._uv(event))
        return True

    def _on_release(self, _widget, event) -> bool:
        if event.button == 1:
            self.editor.release()
        return True

    def _on_scroll(self, _widget, event) -> bool:
        if event.direction == Gdk.ScrollDirection.UP:
            notches = 1
        elif event.direction == Gdk.ScrollDirection.DOWN:
            notches = -1
        elif event.direction == Gdk.ScrollDirection.SMOOTH:
            notches = -round(event.delta_y) if abs(event.delta_y) >= 0.5 else 0
        else:
            return False
        shift = bool(event.state & Gdk.ModifierType.SHIFT_MASK)
        self.editor.scroll(notches, intensity=shift, at=self._uv(event))
        return True

    def _on_key(self, _widget, event) -> bool:
        if event.keyval in (Gdk.KEY_Delete, Gdk.KEY_BackSpace):
            self.editor.remove_selected()
            return True
        return False


class _SelectedLightBox(Gtk.Box):
    """A spin button that shows a value of the selected light (insensitive when none is selected) and sets it
    through the editor: subclasses say which value (:meth:`_show`) and how it is set (:meth:`_set`)."""

    def __init__(self, editor: light_editor.LightMapEditor, spin: Gtk.SpinButton, tooltip: str) -> None:
        super().__init__(spacing=4)
        self.editor, self.spin = editor, spin
        self.spin.set_numeric(True)
        self.spin.set_tooltip_text(tooltip)
        self._showing = False

    def _connect(self) -> None:
        """Follow the spin button and show the selected light (once the subclass has packed its widgets)."""
        self.spin.connect("value-changed", self._on_value)
        self.show_selected()

    def show_selected(self) -> None:
        """Show the selected light's value (insensitive when no light is selected)."""
        index = self.editor.selected
        lights = self.editor.lights.lights
        light = lights[index] if index is not None and index < len(lights) else None
        self.set_sensitive(light is not None)
        if light is None:
            return
        self._showing = True
        try:
            self._show(light)
        finally:
            self._showing = False

    def _on_value(self, spin: Gtk.SpinButton) -> None:
        if not self._showing:  # the editor's change redraws the map, which shows the new value here
            self._set(spin.get_value())

    def _show(self, light: light_map.GaussianLight) -> None:
        raise NotImplementedError

    def _set(self, value: float) -> None:
        raise NotImplementedError


class LightSizeBox(_SelectedLightBox):
    """ "Size" and a spin button in degrees: the selected light's size (the host kit's rule, :mod:`light_size`);
    setting it resizes the light, keeping its power. A Gaussian light's size shows "≈" before it."""

    def __init__(self, editor: light_editor.LightMapEditor) -> None:
        lo, hi = light_size.SIZE_RANGE
        spin = Gtk.SpinButton.new(Gtk.Adjustment.new(lo, lo, hi, 0.1, 1.0, 0.0), 1.0, light_size.DECIMALS)
        super().__init__(editor, spin, light_size.SIZE_HINT)
        self.about = Gtk.Label(label="")
        self.pack_start(Gtk.Label(label="Size:"), False, False, 0)
        self.pack_start(self.about, False, False, 0)
        self.pack_start(self.spin, False, False, 0)
        self.pack_start(Gtk.Label(label=light_size.UNIT), False, False, 0)
        self._connect()

    def _show(self, light: light_map.GaussianLight) -> None:
        self.about.set_text(light_size.size_prefix(light))
        self.spin.set_value(light_size.shown_size(light))
        self.spin.set_increments(*light_size.increments(self.spin.get_value()))

    def _set(self, value: float) -> None:
        self.editor.set_size(value)


class LightIntensityBox(_SelectedLightBox):
    """ "Intensity" and a spin button: the selected light's peak intensity (0 to 3, what Shift+wheel changes);
    setting it is one edit (:meth:`light_editor.LightMapEditor.enter_intensity`)."""

    def __init__(self, editor: light_editor.LightMapEditor) -> None:
        lo, hi = light_map.INTENSITY_RANGE
        step = light_editor.INTENSITY_STEP
        spin = Gtk.SpinButton.new(
            Gtk.Adjustment.new(lo, lo, hi, step, 5 * step, 0.0), step, light_editor.INTENSITY_DECIMALS
        )
        tooltip = (
            "The selected light's intensity, 0 (off) to 3: the brighter a light beside the others, the darker its "
            "shadow. Shift+wheel over the map changes it too."
        )
        super().__init__(editor, spin, tooltip)
        self.pack_start(Gtk.Label(label="Intensity:"), False, False, 0)
        self.pack_start(self.spin, False, False, 0)
        self._connect()

    def _show(self, light: light_map.GaussianLight) -> None:
        self.spin.set_value(light.intensity)

    def _set(self, value: float) -> None:
        self.editor.enter_intensity(value)
