"""One cutout's shadow session: frame once, predict AO once, re-render per light map.

Moving a light re-runs only the shadow renderer (SR); the AO map, and the
user's edits of it, are kept. A shadow that reaches the frame's border is
continued beyond it by the geometric card (:mod:`ssn_engine.long_shadow`).
"""

from __future__ import annotations

import math
from typing import Any

import numpy as np

from . import long_shadow
from .ao_edit import apply_edits
from .framing import CanvasShadow, Framing, frame_alpha, shadow_to_canvas
from .hemisphere import render_light_map
from .host_kit.camera_rules import DEFAULT_FOV, FOV_RANGE
from .host_kit.light_map import LightMap
from .host_kit.shadow_notes import HIDDEN, NO_LIGHT
from .host_kit.sky_map import NETWORK_SHAPE
from .methods import GeometricCard, ShadowMethod
from .methods.base import camera_limits
from .methods.geometric import camera_at


def camera_input(framing: Framing, horizon: float, fov: float = DEFAULT_FOV) -> tuple[float, float]:
    """The frame's camera input for the canvas camera (``horizon`` a canvas row, ``fov`` degrees); a ValueError
    in those terms (canvas rows, degrees) where it lies outside what the methods take (:func:`camera_limits`)."""
    if not math.isfinite(horizon):
        raise ValueError(f"horizon: expected a canvas row (a finite number of pixels from the top), got {horizon}")
    h, f = framing.camera_input(horizon, fov)
    (h_lo, h_hi), (f_lo, f_hi) = camera_limits(framing.n)
    if not h_lo <= h <= h_hi:
        lo, hi = framing.canvas_camera(h_lo, f)[0], framing.canvas_camera(h_hi, f)[0]
        raise ValueError(
            f"horizon: row {horizon:g} is too far from the cutout for the model; give a canvas row from "
            f"{math.ceil(lo)} to {math.floor(hi)}"
        )
    if not f_lo <= f <= f_hi:
        wide, narrow = framing.canvas_camera(h, f_lo)[1], framing.canvas_camera(h, f_hi)[1]
        raise ValueError(
            f"field of view: {fov:g} degrees is outside what the model takes for this cutout on this canvas; "
            f"give {max(FOV_RANGE[0], narrow):.1f} to {min(FOV_RANGE[1], wide):.1f} degrees"
        )
    return h, f


def no_shadow_reason(light_map: LightMap, shadow: CanvasShadow) -> str | None:
    """Why a rendered shadow shows nothing (:data:`NO_LIGHT` or :data:`HIDDEN`), or None when it shows."""
    if light_map.is_dark:
        return NO_LIGHT
    return HIDDEN if shadow.is_empty else None


class ShadowSession:
    """Shadow rendering for one canvas alpha with one method; ``horizon`` (a canvas row) and ``fov`` (the
    canvas's vertical field of view, degrees) give the camera, else the method assumes the default one."""

    def __init__(
        self, alpha: np.ndarray, method: ShadowMethod, horizon: float | None = None, fov: float | None = None
    ) -> None:
        self.method = method
        self.mask, self.framing = frame_alpha(alpha, method.resolution)
        self.edits: list[dict[str, Any]] = []
        self._card: GeometricCard | None = None  # traces long shadows for methods without a card of their own
        self.set_camera(horizon, fov)

    def set_camera(self, horizon: float | None = None, fov: float | None = None) -> None:
        """Change the camera (as in the constructor; None: the method's reading or default one): the AO is
        predicted again with it and the AO edits are applied to it again. The camera the method uses is resolved
        here, once per camera (``used_cameras``), so that a light change resolves none."""
        cameras = None
        if horizon is not None:
            cameras = np.array([camera_input(self.framing, horizon, DEFAULT_FOV if fov is None else fov)])
        elif fov is not None:
            raise ValueError("field of view: give the horizon row too (the camera input needs both)")
        self.cameras = cameras
        self.predicted_ao = self.method.predict_ao(self.mask[None], cameras)[0]
        resolve = getattr(self.method, "cameras_for", None)  # a model's own reading of a blind call's camera
        self.used_cameras = resolve(self.mask[None], cameras) if resolve is not None else cameras
        self.ao = apply_edits(self.predicted_ao, self.edits) if self.edits else self.predicted_ao

    @property
    def camera_read(self) -> dict[str, float] | None:
        """The camera the model read from the outline for a session without one: {"horizon": canvas row, "fov":
        degrees}, where an artist can start to set it; None when a camera was given or the method reads none
        (it then assumes the conventions' default)."""
        return self.camera_read_in(self.framing)

    def camera_read_in(self, framing: Framing) -> dict[str, float] | None:
        """:attr:`camera_read` on the canvas of ``framing`` (this session's, or a preview's scaled copy of it)."""
        if self.cameras is not None or self.used_cameras is None:
            return None
        horizon, fov = framing.canvas_camera(*self.used_cameras[0])
        return {"horizon": float(horizon), "fov": float(fov)}

    def set_ao_edits(self, edits: list[dict[str, Any]]) -> np.ndarray:
        """Replace the list of AO edits; returns the edited AO map."""
        ao = apply_edits(self.predicted_ao, edits)
        self.edits, self.ao = list(edits), ao
        return ao

    def render_frame(self, light_map: LightMap) -> np.ndarray:
        """The frame shadow (N, N) for a light map."""
        elm = render_light_map(light_map, NETWORK_SHAPE[0])
        return self.method.render(self.mask[None], self.ao[None], elm[None], self.used_cameras)[0]

    def to_canvas(
        self, frame: np.ndarray, light_map: LightMap, clip: bool = True, framing: Framing | None = None
    ) -> CanvasShadow:
        """A frame shadow of ``light_map`` at canvas resolution (or on ``framing``'s canvas: a preview's, from
        :meth:`Framing.scaled`), cropped to its visible part; a shadow that reaches the frame's border continues
        beyond it (the geometric card's, :mod:`ssn_engine.long_shadow`)."""
        framing = framing or self.framing
        if not long_shadow.reaches_border(frame):
            return shadow_to_canvas(frame, framing, clip=clip)
        card = self.method if isinstance(self.method, GeometricCard) else getattr(self.method, "card", None)
        if card is None:
            self._card = self._card or GeometricCard(self.method.resolution)
            card = self._card
        elm = render_light_map(light_map, NETWORK_SHAPE[0])
        wide = card.extended_shadow(
            self.mask, elm, camera_at(self.used_cameras, 0), long_shadow.MARGIN, long_shadow.CELL
        )
        window = (*framing.to_frame(0, 0), *framing.to_frame(framing.canvas_width, framing.canvas_height))
        values, origin = long_shadow.extend(frame, wide, window=window if clip else None)
        return shadow_to_canvas(values, framing, origin, clip)

    def render(self, light_map: LightMap, framing: Framing | None = None) -> CanvasShadow:
        """The shadow at canvas resolution, or on ``framing``'s canvas (:meth:`render_frame`, then
        :meth:`to_canvas`)."""
        return self.to_canvas(self.render_frame(light_map), light_map, framing=framing)

    def cover(self, framing: Framing) -> np.ndarray:
        """The cutout's alpha (h, w) on ``framing``'s canvas, resampled from the frame: what hides the shadow
        in a preview."""
        mask = shadow_to_canvas(self.mask, framing, origin=(0.0, 0.0))  # with an origin: no fading at the frame's edges
        return mask.full_canvas(framing.canvas_width, framing.canvas_height)
