"""The views rendered of each item: the paper's grid of cameras, or cameras drawn from continuous ranges."""

from __future__ import annotations

import numpy as np

YAWS = (0.0, 45.0, -45.0, 90.0, -90.0)
PITCHES = (0.0, 15.0, 30.0)
FOV_RANGE = (35.0, 55.0)
PITCH_RANGE = (0.0, 30.0)
VIEWS = 15  # per item, either way
CAMERAS = ("paper", "continuous")


def view_specs() -> list[tuple[float, float]]:
    """The paper's 15 views: (yaw, pitch) for yaw in 0, 45, -45, 90, -90 and pitch in 0, 15, 30."""
    return [(yaw, pitch) for yaw in YAWS for pitch in PITCHES]


def draw_view(k: int, rng: np.random.Generator, cameras: str = "paper") -> tuple[float, float, float]:
    """View k's (yaw, pitch, field of view), degrees. ``paper``: the paper's grid of :func:`view_specs`;
    ``continuous``: yaw uniform in [-180, 180), pitch uniform in ``PITCH_RANGE``. The field of view is uniform in
    ``FOV_RANGE`` and drawn first, so a paper view's stream (and its texel jitter) is what it always was."""
    fov = float(rng.uniform(*FOV_RANGE))
    if cameras == "paper":
        yaw, pitch = view_specs()[k]
    elif cameras == "continuous":
        yaw, pitch = float(rng.uniform(-180.0, 180.0)), float(rng.uniform(*PITCH_RANGE))
    else:
        raise ValueError(f"cameras must be one of {CAMERAS}, got {cameras!r}")
    return yaw, pitch, fov


def pitch_groups(pitches: list[float]) -> list[str]:
    """A group label per view pitch for tables: the pitch itself where every view has one of the paper's
    ``PITCHES``, else its third of ``PITCH_RANGE`` ("0-10", "10-20", "20-30")."""
    if all(p in PITCHES for p in pitches):
        return [f"{p:g}" for p in pitches]
    lo, hi = PITCH_RANGE
    step = (hi - lo) / 3
    bins = [min(2, int((p - lo) // step)) for p in pitches]
    return [f"{lo + b * step:g}-{lo + (b + 1) * step:g}" for b in bins]
