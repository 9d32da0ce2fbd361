"""The light map drawn for the editor (stdlib only): the lights tone-mapped, and the light markers.

Each texel shows its mean radiance under the lights, the light map the
engine gives the model (:func:`.sky_map.map_values`), tone-mapped ``v / (1 + v)``
from night blue to warm white, as packed RGB bytes that a host shows as a
QImage or a GdkPixbuf. Only the rows and columns where a light is above
``CUTOFF`` are visited, so a 192 x 96 picture of a few lights costs a few
milliseconds.
"""

from __future__ import annotations

import math

from .light_map import LightMap
from .sky_map import map_values

NIGHT = (0.10, 0.13, 0.20)
LIGHT = (1.0, 0.96, 0.85)
PICTURE_SIZE = (192, 96)  # what the editors draw, scaled to the widget
CUTOFF = 1e-3  # a light's factor below which a row or column is left out

MARKER = (255, 255, 255)
SELECTED_MARKER = (255, 200, 0)
GUIDE = (110, 110, 130)

_LUT = [
    bytes(round(255 * (n + (b - n) * k / 255)) for n, b in zip(NIGHT, LIGHT, strict=True)) for k in range(256)
]  # RGB of 256 tone levels


def map_rgb(lights: LightMap, width: int = PICTURE_SIZE[0], height: int = PICTURE_SIZE[1]) -> bytes:
    """RGB888 bytes (height x width x 3) of the tone-mapped light map."""
    dark = _LUT[0] * width
    return b"".join(
        b"".join([_LUT[int(255 * v / (1.0 + v) + 0.5)] for v in row]) if any(row) else dark
        for row in map_values(lights, width, height, CUTOFF)
    )


def _put(rgb: bytearray, width: int, height: int, x: int, y: int, colour: tuple[int, int, int]) -> None:
    if 0 <= y < height:
        x %= width  # the map wraps around in azimuth
        i = 3 * (y * width + x)
        rgb[i : i + 3] = bytes(colour)


def overlay_markers(rgb: bytearray, width: int, height: int, lights: LightMap, selected: int | None) -> bytearray:
    """Draw guides and a ring per light (radius = one sigma, at least 4 px) onto packed RGB bytes, for hosts
    without a vector painter (GIMP's Python has no cairo).

    Guides: the vertical line at u = 0.5 (the sky behind the object) and the
    quarter lines. Returns ``rgb`` (modified in place).
    """
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
