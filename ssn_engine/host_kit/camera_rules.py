"""The camera rules every front end shares (stdlib only): the bounds of a camera, its default, and how a host
scales, rounds and describes one.

A camera is the image's horizon row (canvas pixels from the top edge, which may lie outside the canvas) and its
vertical field of view in degrees (conventions, "Camera input"). Two ranges of field of view are in use, each
defined here once:

- :data:`FOV_RANGE`, what the engine accepts (the worker's ``camera``, the CLI's ``--fov``, the camera input of
  :func:`ssn_engine.predict_frames` converted to a focal length): every lens a pinhole can have, short of the
  degenerate 0 and 180 degrees;
- :data:`EDITOR_FOV_RANGE`, what the hosts' editors offer (the Krita docker's field, the GIMP filter's
  argument): the lenses of photographs, from a long telephoto to an ultra-wide, inside the engine's range.

A camera the model reads from an outline (``camera_read``) may lie outside the editors' range; it is clamped to
it where an editor shows it (:func:`camera_read_settings`).
"""

from __future__ import annotations

import math

__all__ = [
    "DEFAULT_FOV",
    "EDITOR_FOV_RANGE",
    "EDITOR_HORIZON_RANGE",
    "FOV_RANGE",
    "NO_GUIDE",
    "camera_read_note",
    "camera_read_settings",
    "check_fov",
    "horizon_from_guides",
    "preview_size",
    "row_from_preview",
    "scaled_camera",
    "within",
]

DEFAULT_FOV = 45.0  # degrees: the conventions' default camera, and the editors' starting value
FOV_RANGE = (1.0, 170.0)  # degrees: the fields of view the engine accepts
EDITOR_FOV_RANGE = (10.0, 120.0)  # degrees: the fields of view the hosts' editors offer
EDITOR_HORIZON_RANGE = (-100000.0, 100000.0)  # canvas rows the hosts' editors offer for the horizon
NO_GUIDE = "Add a horizontal guide on the horizon first (drag one down from the top ruler), then press From guide."


def check_fov(fov: object, name: str = "field of view") -> float:
    """``fov`` as a float when it is a number of degrees inside :data:`FOV_RANGE`, else ValueError naming
    ``name``."""
    lo, hi = FOV_RANGE
    if isinstance(fov, bool) or not isinstance(fov, (int, float)) or not math.isfinite(fov) or not lo <= fov <= hi:
        raise ValueError(f"{name}: expected {lo:g} to {hi:g} degrees, got {fov!r}")
    return float(fov)


def preview_size(width: int, height: int, limit: int, height_limit: int | None = None) -> tuple[int, int, float]:
    """The size of a preview's background (a ``preview`` request's thumbnail) for a ``width`` x ``height``
    canvas, and its scale: the longer side at most ``limit`` (and the height at most ``height_limit``, when
    given), the aspect kept as the worker expects (each side rounded)."""
    scale = min(1.0, limit / max(width, height, 1))
    if height_limit is not None:
        scale = min(scale, height_limit / max(height, 1))
    return max(1, round(width * scale)), max(1, round(height * scale)), scale


def row_from_preview(y: float, scale: float) -> float:
    """The canvas row (a whole row) shown at row ``y`` of a preview drawn at ``scale`` (a click on the preview
    that puts the horizon there)."""
    return within(round(y / scale), EDITOR_HORIZON_RANGE)


def horizon_from_guides(rows: list[float]) -> float | None:
    """The horizon row a host takes from the image's horizontal guides (canvas rows, in the host's order): the
    first one, a whole row; None without a guide (say :data:`NO_GUIDE`)."""
    return within(round(rows[0]), EDITOR_HORIZON_RANGE) if rows else None


def scaled_camera(camera: dict[str, float], scale: float) -> dict[str, float]:
    """A canvas camera on the canvas scaled by ``scale`` (a preview's thumbnail): the horizon row scales, the
    field of view does not."""
    return {**camera, "horizon": camera["horizon"] * scale}


def within(value: float, bounds: tuple[float, float]) -> float:
    """``value`` as a float clamped to ``bounds`` (lo, hi)."""
    return float(min(max(value, bounds[0]), bounds[1]))


def camera_read_settings(read: dict[str, float]) -> dict[str, float]:
    """The editor's ``horizon`` and ``fov`` for a camera the model read from an outline (``camera_read``, canvas
    rows): whole rows and degrees within the editors' bounds, where the horizon option starts when turned on."""
    return {
        "horizon": within(round(read["horizon"]), EDITOR_HORIZON_RANGE),
        "fov": within(round(read["fov"]), EDITOR_FOV_RANGE),
    }


def camera_read_note(read: dict[str, float], image_height: int) -> str:
    """What a host says of a camera the model read (:func:`camera_read_settings`, canvas rows): where its horizon
    is drawn in the preview (dotted blue), or that it lies above or below the image, where no preview shows it."""
    shown = camera_read_settings(read)
    horizon = shown["horizon"]
    where = "dotted blue" if 0 <= horizon < image_height else ("above the image" if horizon < 0 else "below the image")
    return (
        f"Camera read from the cutout's outline: horizon at row {horizon:.0f} ({where}), {shown['fov']:.0f}° "
        "field of view. If the shadow's perspective looks wrong, set the image's horizon."
    )
