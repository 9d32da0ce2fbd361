"""One cutout's shadow session: frame once, predict AO once, re-render per light map.

Moving a light re-runs only the shadow renderer (SR); the AO map, and the
user's edits of it, are kept.
"""

from __future__ import annotations

from typing import Any

import numpy as np

from .ao_edit import apply_edits
from .framing import CanvasShadow, Framing, frame_alpha, shadow_to_canvas
from .hemisphere import NETWORK_SHAPE, render_light_map
from .light_map import LightMap
from .methods import ShadowMethod


class ShadowSession:
    """Shadow rendering for one canvas alpha with one method."""

    def __init__(self, alpha: np.ndarray, method: ShadowMethod) -> None:
        self.method = method
        self.mask, self.framing = frame_alpha(alpha, method.resolution)
        self.predicted_ao = method.predict_ao(self.mask[None])[0]
        self.edits: list[dict[str, Any]] = []
        self.ao = self.predicted_ao

    @property
    def frame(self) -> Framing:
        return self.framing

    def set_ao_edits(self, edits: list[dict[str, Any]]) -> np.ndarray:
        """Replace the list of AO edits; returns the edited AO map."""
        ao = apply_edits(self.predicted_ao, edits)
        self.edits, self.ao = list(edits), ao
        return ao

    def render_frame(self, light_map: LightMap) -> np.ndarray:
        """The frame shadow (N, N) for a light map."""
        elm = render_light_map(light_map, NETWORK_SHAPE[0])
        return self.method.render(self.mask[None], self.ao[None], elm[None])[0]

    def render(self, light_map: LightMap) -> CanvasShadow:
        """The shadow at canvas resolution, cropped to its visible part."""
        return shadow_to_canvas(self.render_frame(light_map), self.framing)
