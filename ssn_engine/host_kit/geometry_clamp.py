"""The hosts' lift and thickness controls: a value out of range clamped, with the reason for people (stdlib only).

The engine refuses what :mod:`.geometry_rules` does not take (conventions, "Lift and thickness"); a host's control
clamps to it first and says why: a lift of 0 to ``MAX_LIFT_HEIGHTS`` canvas heights whose ground lies below the
horizon of the camera in use (the engine's rule: a lift above 0 puts the ground beneath the cutout's lowest row
``lowest`` at ``lowest + lift``, which must lie below ``horizon``), a thickness in ``THICKNESS_RANGE``.
"""

from __future__ import annotations

import math

from .geometry_rules import MAX_LIFT_HEIGHTS, THICKNESS_RANGE, ground_above_horizon, max_lift

__all__ = ["clamp_lift", "clamp_thickness", "lowest_lift"]

MARGIN = 0.01  # rows: a lift this close to the horizon's is taken past it (the engine's row is a float)


def lowest_lift(lowest: float, horizon: float) -> float:
    """The smallest lift above 0 that puts the ground beneath a cutout whose lowest row is ``lowest`` below the
    horizon at row ``horizon`` (whole rows; 0 where the cutout's foot already lies below it)."""
    gap = horizon - lowest
    return float(math.floor(gap + MARGIN) + 1) if gap >= 0 else 0.0


def clamp_lift(
    value: float, canvas_height: int, lowest: float | None = None, horizon: float | None = None
) -> tuple[float, str]:
    """``value`` (canvas rows) clamped to what the engine takes on a canvas ``canvas_height`` rows tall, given the
    cutout's lowest row and the horizon of the camera in use where known; and why it was clamped ("" if not)."""
    most = max_lift(canvas_height)
    lift = float(value) if math.isfinite(value) else 0.0
    if lift < 0:
        return 0.0, f"Lift: {value:g} px is no distance below the object; set to 0 (it rests on the ground)."
    if lift > most:
        return most, (
            f"Lift: {lift:g} px is more than {MAX_LIFT_HEIGHTS:g} canvas heights ({most:g} px, the most the engine "
            f"takes); set to {most:g}."
        )
    if lowest is not None and horizon is not None and ground_above_horizon(lowest, lift, horizon):
        least = min(most, lowest_lift(lowest, horizon))
        return least, (
            f"Lift: {lift:g} px puts the ground beneath the object at row {lowest + lift:.0f}, at or above the horizon "
            f"(row {horizon:.0f}); the ground lies below it, so the lift is raised to {least:g} (0 rests it on the "
            "ground)."
        )
    return lift, ""


def clamp_thickness(value: float) -> tuple[float, str]:
    """``value`` clamped to ``THICKNESS_RANGE``, and why ("" if not)."""
    lo, hi = THICKNESS_RANGE
    thickness = float(value) if math.isfinite(value) else lo
    if lo <= thickness <= hi:
        return thickness, ""
    clamped = min(hi, max(lo, thickness))
    return (
        clamped,
        f"Thickness: {value:g} is outside {lo:g} (flat) to {hi:g} (deep), the engine's range; set to {clamped:g}.",
    )
