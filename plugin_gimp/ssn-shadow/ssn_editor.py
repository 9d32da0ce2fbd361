"""The light-map editor's interaction logic, toolkit-free (the GTK widget only forwards events).

Map coordinates as in ``light_map``: ``u`` across (0.5 = behind the object),
``v`` down from the zenith. Gestures: press on empty sky adds a light, press
on a light selects it and dragging moves it; the wheel changes the selected
light's softness (size), with Shift its intensity; right-click or Delete
removes a light. ``on_change(final)`` is called after every change: ``final``
is False while dragging (redraw) and True when an edit is complete
(re-render the preview).
"""

from __future__ import annotations

from collections.abc import Callable

from ssn_engine_link import light_map

NEW_SOFTNESS = 0.01
NEW_INTENSITY = 2.0
SOFTNESS_STEP = 1.25  # per wheel notch, multiplicative
INTENSITY_STEP = 0.1  # per wheel notch with Shift


class LightMapEditor:
    """Edits a :class:`light_map.LightMap` in response to pointer gestures."""

    def __init__(
        self, lights: light_map.LightMap | None = None, on_change: Callable[[bool], None] | None = None
    ) -> None:
        self.lights = lights if lights is not None else light_map.preset(light_map.DEFAULT_PRESET)
        self.on_change = on_change
        self.selected: int | None = None
        self._grab: tuple[float, float] | None = None  # pointer offset from the dragged light's centre
        self._moved = False
        self.message = ""  # the last refusal (e.g. too many lights), for a status line

    def _changed(self, final: bool) -> None:
        if self.on_change is not None:
            self.on_change(final)

    # -- gestures --------------------------------------------------------------
    def press(self, u: float, v: float) -> None:
        """Select the light under the pointer and start dragging it, or add one on empty sky."""
        self.message = ""
        hit = self.lights.hit_test(u, v)
        if hit is None:
            try:
                hit = self.lights.add(u, v, NEW_SOFTNESS, NEW_INTENSITY)
            except light_map.LightMapError as exc:
                self.message = str(exc)
                self.selected = None
                return
            self._changed(True)
        self.selected = hit
        light = self.lights.lights[hit]
        du = (u - light.u + 0.5) % 1.0 - 0.5
        self._grab = (du, v - light.v)
        self._moved = False
        self._changed(False)

    def drag(self, u: float, v: float) -> None:
        """Move the grabbed light so that it keeps its offset from the pointer."""
        if self._grab is None or self.selected is None:
            return
        self.lights.move(self.selected, u - self._grab[0], v - self._grab[1])
        self._moved = True
        self._changed(False)

    def release(self) -> None:
        """End a drag; a moved light is a complete edit."""
        moved, self._grab, self._moved = self._moved, None, False
        if moved:
            self._changed(True)

    def scroll(self, notches: int, intensity: bool = False) -> None:
        """Wheel on the selected light: softness (size) up/down, or intensity with ``intensity``."""
        if self.selected is None or notches == 0:
            return
        light = self.lights.lights[self.selected]
        if intensity:
            self.lights.reweight(self.selected, light.intensity + INTENSITY_STEP * notches)
        else:
            self.lights.resize(self.selected, light.softness * SOFTNESS_STEP**notches)
        self._changed(True)

    def remove_at(self, u: float, v: float) -> None:
        """Remove the light under the pointer, if any."""
        hit = self.lights.hit_test(u, v)
        if hit is not None:
            self._remove(hit)

    def remove_selected(self) -> None:
        if self.selected is not None:
            self._remove(self.selected)

    def _remove(self, index: int) -> None:
        self.lights.delete(index)
        self.selected = None
        self._grab = None
        self._changed(True)

    # -- whole map ---------------------------------------------------------------
    def load(self, lights: light_map.LightMap) -> None:
        """Replace the map (e.g. a preset was chosen)."""
        self.lights, self.selected, self._grab = lights, None, None
        self._changed(True)

    def to_json(self) -> str:
        """The light map as the procedure's ``light-map`` argument (compact JSON)."""
        import json

        return json.dumps(self.lights.to_dict(), separators=(",", ":"))


# -- drawing (toolkit-free: the widget shows the bytes as a pixbuf) -------------------------------
MARKER = (255, 255, 255)
SELECTED_MARKER = (255, 200, 0)
GUIDE = (110, 110, 130)


def _put(rgb: bytearray, width: int, height: int, x: int, y: int, colour: tuple[int, int, int]) -> None:
    if 0 <= y < height:
        x %= width  # the map wraps around in azimuth
        i = 3 * (y * width + x)
        rgb[i : i + 3] = bytes(colour)


def overlay_markers(
    rgb: bytearray, width: int, height: int, lights: light_map.LightMap, selected: int | None
) -> bytearray:
    """Draw guides and a ring per light (radius = one sigma, at least 4 px) onto packed RGB bytes.

    Guides: the vertical line at u = 0.5 (the sky behind the object) and the
    quarter lines. Returns ``rgb`` (modified in place).
    """
    import math

    for u in (0.25, 0.5, 0.75):
        x = min(width - 1, round(u * width))
        for y in range(0, height, 1 if u == 0.5 else 3):
            _put(rgb, width, height, x, y, GUIDE)
    for index, light in enumerate(lights):
        colour = SELECTED_MARKER if index == selected else MARKER
        cx, cy = light.u * width, light.v * height
        radius = max(4.0, light.radius * height)
        steps = max(24, int(2 * math.pi * radius))
        for k in range(steps):
            t = 2 * math.pi * k / steps
            _put(rgb, width, height, round(cx + radius * math.cos(t)), round(cy + radius * math.sin(t)), colour)
        for d in (-1, 0, 1):  # centre cross
            _put(rgb, width, height, round(cx) + d, round(cy), colour)
            _put(rgb, width, height, round(cx), round(cy) + d, colour)
    return rgb
