"""A light's size as both editors show and edit it: an angle in degrees (stdlib only).

The Krita docker and the GIMP dialog each have a *Size* spin box for the
selected light and label every light on the map; this module is the rule they
share. A size is the apparent diameter of a uniform disk light (conventions,
"Light size"), within ``SIZE_RANGE`` (the light-map file's bounds), shown
with ``DECIMALS`` decimals so that the sun's 0.53 is exact. The spin box's
arrows step by a tenth of the value's decade (0.53: 0.01; 3: 0.1; 16: 1) and
its page keys by the decade; one wheel notch on the map scales the size by
``WHEEL_STEP``. Setting a size keeps the light's power (:meth:`.LightMap.set_angle`).
A Gaussian light (an older file's ``softness``) has no edge: it shows the
diameter of the disk as wide (:attr:`.GaussianLight.size_degrees`), marked
"about" (``≈``), and becomes a disk when its size is set.
"""

from __future__ import annotations

import math

from .light_map import ANGLE_RANGE, GaussianLight

__all__ = [
    "DECIMALS",
    "SIZE_RANGE",
    "UNIT",
    "WHEEL_STEP",
    "clamp_size",
    "SIZE_HINT",
    "increments",
    "shown_size",
    "size_prefix",
    "size_text",
    "wheel_size",
]

SIZE_RANGE = ANGLE_RANGE  # degrees
DECIMALS = 2
UNIT = "\N{DEGREE SIGN}"
ABOUT = "\N{ALMOST EQUAL TO}"  # a Gaussian's size: the disk as wide
WHEEL_STEP = 1.25  # one wheel notch scales a disk light's diameter by this
SIZE_HINT = (
    "The selected light's apparent diameter in degrees: the sun 0.53, a hazy sun about 3, a softbox 10 to 30. "
    "The smaller the light, the crisper its shadow; its power stays the same."
)


def clamp_size(angle: float) -> float:
    """``angle`` degrees within ``SIZE_RANGE``, to ``DECIMALS`` decimals: a size the spin box can show."""
    return round(min(max(angle, SIZE_RANGE[0]), SIZE_RANGE[1]), DECIMALS)


def increments(angle: float) -> tuple[float, float]:
    """The spin box's (step, page) at ``angle`` degrees: a tenth of its decade and the decade (at least the last
    decimal shown)."""
    decade = 10.0 ** math.floor(math.log10(max(angle, SIZE_RANGE[0])) + 1e-9)
    return max(decade / 10.0, 10.0**-DECIMALS), decade


def shown_size(light: GaussianLight) -> float:
    """The value the spin box shows for ``light``: its diameter in degrees, within ``SIZE_RANGE``, to
    ``DECIMALS`` decimals."""
    return clamp_size(light.size_degrees)


def wheel_size(angle: float, notches: float) -> float:
    """A disk light's diameter after ``notches`` wheel notches (up: larger), to the decimals shown."""
    return clamp_size(angle * WHEEL_STEP**notches)


def _number(angle: float, decimals: int) -> str:
    return f"{angle:.{decimals}f}".rstrip("0").rstrip(".")


def size_prefix(light: GaussianLight) -> str:
    """What the spin box shows before the size: "≈" for a Gaussian light (it has no edge), else nothing."""
    return "" if light.angle is not None else ABOUT


def size_text(light: GaussianLight) -> str:
    """The light's size label on the map: "0.53°" for a disk; for a Gaussian, the disk as wide, "≈23°"."""
    if light.angle is not None:
        return _number(light.angle, DECIMALS) + UNIT
    return ABOUT + _number(light.size_degrees, 1 if light.size_degrees < 10 else 0) + UNIT
