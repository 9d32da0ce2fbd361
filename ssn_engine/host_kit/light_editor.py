"""The light-map editor's gestures, toolkit-free (stdlib only): both plug-ins' widgets forward events here.

Map coordinates as in :mod:`light_map`: ``u`` across (0.5 = behind the
object), ``v`` down from the zenith. Gestures: a press on empty sky adds a
light of the loaded map's kind (:func:`new_light_angle`: a disk of the sun's
0.53 degrees after the sun preset, a Gaussian after a preset of Gaussians), a
press on a light selects it and dragging moves it (keeping the grab
offset); the wheel changes the size of the light under the pointer or else of
the selected one (a Gaussian's softness, a disk light's angle in degrees, as
:mod:`light_size` steps it), with Shift its intensity; right-click or Delete
removes a light. A Size box sets the selected light's diameter in degrees, an
Intensity box its intensity.

After every change ``on_change(live, new_stroke)`` is called: ``live`` while
a light is being dragged or a slider moved (redraw, preview at once), not
when an edit is complete (a press that added a light, a release after a drag,
a wheel notch, a size or intensity typed, a removal, a new map); ``new_stroke`` when the change starts a
new undo step. ``on_select(index)`` follows a change of the selected light
(None: no light selected).
"""

from __future__ import annotations

import json
import time
from collections.abc import Callable

from . import light_map, light_size

NEW_SOFTNESS = 0.01  # a new light's softness where the map's lights are Gaussians (about 36 degrees wide)
NEW_INTENSITY = 2.0
INTENSITY_DECIMALS = 2  # an Intensity box shows (and sets) this many decimals
SOFTNESS_STEP = 1.25  # per wheel notch, multiplicative
INTENSITY_STEP = 0.1  # per wheel notch with Shift
STROKE_GAP_S = 0.6  # wheel notches (or size or intensity steps) further apart than this start a new undo step

OnChange = Callable[[bool, bool], None]
OnSelect = Callable[[int | None], None]


def new_light_angle(lights: light_map.LightMap, before: float | None) -> float | None:
    """The diameter in degrees of the disk light a click on empty sky adds once ``lights`` are loaded (a preset
    chosen, a file read), or None for a Gaussian of ``NEW_SOFTNESS``: the map's first disk light's angle (the sun
    preset: 0.53; the softbox: 16); None where its lights are all Gaussians (an older file, the overcast preset);
    ``before`` where it has no lights."""
    if not len(lights):
        return before
    return next((light.angle for light in lights if light.angle is not None), None)


class LightMapEditor:
    """Edits a :class:`light_map.LightMap` in response to pointer gestures and slider moves."""

    def __init__(
        self,
        lights: light_map.LightMap | None = None,
        on_change: OnChange | None = None,
        on_select: OnSelect | None = None,
        clock: Callable[[], float] = time.monotonic,
    ) -> None:
        self.lights = lights if lights is not None else light_map.preset(light_map.DEFAULT_PRESET)
        self.on_change, self.on_select, self._clock = on_change, on_select, clock
        self.selected: int | None = 0 if len(self.lights) else None
        default = new_light_angle(light_map.preset(light_map.DEFAULT_PRESET), None)
        self.new_angle = new_light_angle(self.lights, default)  # the lights a click adds (None: a Gaussian)
        self._grab: tuple[float, float] | None = None  # pointer offset from the dragged light's centre
        self._dragged = False  # the grabbed light has moved since the press
        self._stroke_open = False  # the next move continues the undo step a press started
        self._last_wheel = -1e9
        self.message = ""  # the last refusal (e.g. too many lights), for a status line

    @property
    def dragging(self) -> bool:
        """A grabbed light is being moved (until the release)."""
        return self._grab is not None and self._dragged

    def _changed(self, live: bool, new_stroke: bool) -> None:
        if self.on_change is not None:
            self.on_change(live, new_stroke)

    def select(self, index: int | None) -> None:
        """Select a light (None: none)."""
        if index != self.selected:
            self.selected = index
            if self.on_select is not None:
                self.on_select(index)

    # -- gestures --------------------------------------------------------------
    def press(self, u: float, v: float) -> None:
        """Select the light under the pointer and grab it, or add one on empty sky (a complete edit)."""
        self.message = ""
        hit = self.lights.hit_test(u, v)
        added = hit is None
        if hit is None:
            try:
                hit = self.lights.add(u, v, NEW_SOFTNESS, NEW_INTENSITY, self.new_angle)
            except light_map.LightMapError as exc:
                self.message = str(exc)
                self.select(None)
                return
        self.select(hit)
        light = self.lights.lights[hit]
        du = (u - light.u + 0.5) % 1.0 - 0.5
        self._grab, self._dragged, self._stroke_open = (du, v - light.v), False, added
        if added:
            self._changed(False, True)

    def drag(self, u: float, v: float) -> None:
        """Move the grabbed light so that it keeps its offset from the pointer; the first move of a light that
        was already there starts a new undo step (a light just added moves within its own)."""
        if self._grab is None or self.selected is None:
            return
        self.lights.move(self.selected, u - self._grab[0], v - self._grab[1])
        first = not self._dragged and not self._stroke_open
        self._dragged = True
        self._changed(True, first)

    def release(self) -> None:
        """End a drag; a light that moved is a complete edit."""
        dragged, self._grab, self._dragged, self._stroke_open = self._dragged, None, False, False
        if dragged:
            self._changed(False, False)

    def scroll(self, notches: float, intensity: bool = False, at: tuple[float, float] | None = None) -> None:
        """Wheel: the size (a Gaussian's softness, a disk light's angle; or with ``intensity`` the intensity) of
        the light under ``at``, else the selected one. Notches in quick succession are one undo step."""
        target = self.lights.hit_test(*at) if at is not None else None
        target = self.selected if target is None else target
        if target is None or notches == 0:
            return
        self.select(target)
        light = self.lights.lights[target]
        if intensity:
            self.lights.reweight(target, light.intensity + INTENSITY_STEP * notches)
        elif light.angle is not None:
            self.lights.set_angle(target, light_size.wheel_size(light.angle, notches))
        else:
            self.lights.resize(target, light.softness * SOFTNESS_STEP**notches)
        self._step_done()

    def _step_done(self) -> None:
        """A wheel notch or size step is a complete edit; steps in quick succession are one undo step."""
        now = self._clock()
        new_stroke, self._last_wheel = now - self._last_wheel > STROKE_GAP_S, now
        self._changed(False, new_stroke)

    def remove_at(self, u: float, v: float) -> None:
        """Remove the light under the pointer, if any."""
        hit = self.lights.hit_test(u, v)
        if hit is not None:
            self._remove(hit)

    def remove_selected(self) -> None:
        if self.selected is not None and self.selected < len(self.lights):
            self._remove(self.selected)

    def _remove(self, index: int) -> None:
        self.lights.delete(index)
        self._grab = None
        self.select(None)
        self._changed(False, True)

    # -- controls ----------------------------------------------------------------
    def set_size(self, degrees: float) -> None:
        """The selected light's diameter in degrees (the Size box), to the decimals it shows; its power is kept
        (a Gaussian light becomes a disk). Nothing happens if the light already has that size, so a box that
        shows a light's size does not edit it. Steps in quick succession are one undo step."""
        if self.selected is None:
            return
        light = self.lights.lights[self.selected]
        angle = light_size.clamp_size(degrees)
        if light.angle == angle:
            return
        self.lights.set_angle(self.selected, angle)
        self._step_done()

    def set_intensity(self, intensity: float, new_stroke: bool) -> None:
        """The selected light's intensity (a slider moved)."""
        if self.selected is not None:
            self.lights.reweight(self.selected, intensity)
            self._changed(True, new_stroke)

    def enter_intensity(self, intensity: float) -> None:
        """The selected light's intensity typed or stepped in an Intensity box, to ``INTENSITY_DECIMALS``
        decimals within ``INTENSITY_RANGE``: a complete edit (as :meth:`set_size`). Nothing happens if the light
        shows that intensity already, so a box that shows a light's intensity does not edit it. Steps in quick
        succession are one undo step."""
        if self.selected is None:
            return
        lo, hi = light_map.INTENSITY_RANGE
        intensity = round(min(max(intensity, lo), hi), INTENSITY_DECIMALS)
        if round(self.lights.lights[self.selected].intensity, INTENSITY_DECIMALS) == intensity:
            return
        self.lights.reweight(self.selected, intensity)
        self._step_done()

    # -- whole map ---------------------------------------------------------------
    def load(self, lights: light_map.LightMap) -> None:
        """Replace the map (a preset was chosen, or the settings were reset): one new undo step. A click then adds
        a light of its kind (:func:`new_light_angle`)."""
        self.lights, self._grab = lights, None
        self.new_angle = new_light_angle(lights, self.new_angle)
        self.select(0 if len(lights) else None)
        self._changed(False, True)

    def to_json(self) -> str:
        """The light map as compact JSON (GIMP's ``light-map`` argument)."""
        return json.dumps(self.lights.to_dict(), separators=(",", ":"))
