"""The artist's geometry every front end shares (stdlib only): lift and thickness, their ranges and checks.

Conventions, "Lift and thickness": the lift L is canvas rows from the cutout's lowest point down to the image of
the ground point beneath it (0: the object rests on the ground); the thickness T is the object's extent along
the view over its extent across it (0 a flat sign facing the camera, 1 a ball, about 2 a person seen from the
side). Without T the engine reads it from the outline. The CLI and the worker refuse a value outside these ranges
with the message of :func:`check_lift` or :func:`check_thickness`; the hosts clamp their controls to them.
"""

from __future__ import annotations

import math

__all__ = ["MAX_LIFT_HEIGHTS", "THICKNESS_RANGE", "check_lift", "check_thickness", "ground_above_horizon", "max_lift"]

MAX_LIFT_HEIGHTS = 20.0  # a lift of at most this many canvas heights: beyond it the foot is nowhere on the picture
THICKNESS_RANGE = (0.0, 8.0)  # a flat sign to a rod seen end-on


def _number(value: object) -> float | None:
    """``value`` as a float when it is a finite number (not a bool), else None."""
    if isinstance(value, bool) or not isinstance(value, (int, float)) or not math.isfinite(value):
        return None
    return float(value)


def max_lift(canvas_height: int) -> float:
    """The largest lift the engine takes on a canvas ``canvas_height`` rows tall: :data:`MAX_LIFT_HEIGHTS` of it."""
    return MAX_LIFT_HEIGHTS * max(1, int(canvas_height))


def ground_above_horizon(lowest: float, lift: float, horizon: float) -> bool:
    """Whether a lift of ``lift`` puts the ground beneath a cutout whose lowest row is ``lowest`` at or above the
    horizon at row ``horizon`` (canvas rows), which the engine refuses: resting (0) is always taken."""
    return lift > 0 and lowest + lift <= horizon


def check_lift(value: object, canvas_height: int, name: str = "lift") -> float:
    """``value`` as a float when it is a lift the engine takes on a canvas ``canvas_height`` rows tall (0 to
    :func:`max_lift`), else ValueError naming ``name`` and the range."""
    most = max_lift(canvas_height)
    lift = _number(value)
    if lift is None or not 0.0 <= lift <= most:
        raise ValueError(
            f"{name}: expected 0 to {most:g} canvas pixels (rows from the cutout's lowest point down to the ground "
            f"beneath it; 0 rests on the ground), got {value!r}"
        )
    return lift


def check_thickness(value: object, name: str = "thickness") -> float:
    """``value`` as a float when it is a thickness in :data:`THICKNESS_RANGE`, else ValueError naming ``name``."""
    lo, hi = THICKNESS_RANGE
    thickness = _number(value)
    if thickness is None or not lo <= thickness <= hi:
        raise ValueError(
            f"{name}: expected {lo:g} to {hi:g} (depth along the view over width across it: 0 a flat sign, 1 a "
            f"ball, 2 a person seen from the side), got {value!r}"
        )
    return thickness
