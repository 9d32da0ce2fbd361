"""User refinement of the AO map (the paper's control near contact points).

Edits are plain dicts (JSON-ready, so the plug-ins keep them as an undo
list) applied in order to the predicted AO map. Positions and radii are
fractions of the N x N frame (x right, y down); AO follows the conventions
(1 fully exposed, 0 touching the object).
"""

from __future__ import annotations

from typing import Any

import numpy as np

from .host_kit import defaults
from skimage.morphology import dilation, disk, erosion

MAX_GROW = 32  # frame pixels
MAX_STRENGTH = defaults.MAX_AO_STRENGTH


class AOEditError(ValueError):
    """A malformed AO edit; the message names the field."""


def brush(ao: np.ndarray, x: float, y: float, radius: float, strength: float) -> np.ndarray:
    """Soft round brush: strength < 0 darkens towards 0, > 0 lightens towards 1."""
    n = ao.shape[0]
    rows, cols = np.mgrid[0:n, 0:n]
    r = max(radius * n, 0.5)
    d2 = ((cols + 0.5 - x * n) ** 2 + (rows + 0.5 - y * n) ** 2) / (r * r)
    weight = np.where(d2 < 1.0, (1.0 - d2) ** 2, 0.0) * abs(strength)
    target = 1.0 if strength > 0 else 0.0
    return (ao + weight * (target - ao)).astype(np.float32)


def grow(ao: np.ndarray, pixels: int) -> np.ndarray:
    """Grow the dark (occluded) region by ``pixels`` frame pixels; negative shrinks it."""
    if pixels == 0:
        return ao
    footprint = disk(abs(pixels))
    return (erosion(ao, footprint) if pixels > 0 else dilation(ao, footprint)).astype(np.float32)


def scale_strength(ao: np.ndarray, value: float) -> np.ndarray:
    """Scale the occlusion 1 - AO by ``value`` (0 removes it, 1 keeps it)."""
    return (1.0 - np.clip(value * (1.0 - ao), 0.0, 1.0)).astype(np.float32)


def _field(edit: dict, key: str, where: str, lo: float, hi: float) -> float:
    value = edit.get(key)
    if isinstance(value, bool) or not isinstance(value, (int, float)) or not np.isfinite(value):
        raise AOEditError(f"{where}.{key}: expected a number, got {value!r}")
    if not lo <= value <= hi:
        raise AOEditError(f"{where}.{key}: expected a number in [{lo:g}, {hi:g}], got {value!r}")
    return float(value)


def apply_edits(ao: np.ndarray, edits: list[dict[str, Any]]) -> np.ndarray:
    """Apply a list of edits in order; returns a new AO map clipped to [0, 1]."""
    if not isinstance(edits, (list, tuple)):
        raise AOEditError(f"edits: expected a list of edits, got {type(edits).__name__}")
    out = np.asarray(ao, np.float32).copy()
    for i, edit in enumerate(edits):
        where = f"edits[{i}]"
        if not isinstance(edit, dict):
            raise AOEditError(f"{where}: expected an object")
        op = edit.get("op")
        if op == "brush":
            out = brush(
                out,
                _field(edit, "x", where, -1.0, 2.0),
                _field(edit, "y", where, -1.0, 2.0),
                _field(edit, "radius", where, 0.0, 1.0),
                _field(edit, "strength", where, -1.0, 1.0),
            )
        elif op == "grow":
            out = grow(out, int(round(_field(edit, "pixels", where, -MAX_GROW, MAX_GROW))))
        elif op == "strength":
            out = scale_strength(out, _field(edit, "value", where, 0.0, MAX_STRENGTH))
        else:
            raise AOEditError(f"{where}.op: expected 'brush', 'grow' or 'strength', got {op!r}")
    return np.clip(out, 0.0, 1.0)
