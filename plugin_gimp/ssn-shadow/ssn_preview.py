"""Dialog preview maths, toolkit-free: the shadow multiplied onto a small RGB(A) thumbnail.

The preview casts the shadow of a thumbnail-sized cutout (the same framing
scales with the cutout, so its geometry matches the full-size result) and
composites it like GIMP's Multiply layer would, in the thumbnail's 8-bit
values: ``out = bg * (1 - a * (1 - colour))``. The real shadow layer lies
below the cutout, so where the cutout covers the thumbnail (``cover``, its
8-bit alpha) the shadow is hidden in proportion.
"""

from __future__ import annotations

import math

PREVIEW_SIZE = 384


def preview_size(width: int, height: int, limit: int = PREVIEW_SIZE) -> tuple[int, int, float]:
    """Thumbnail width, height and scale for a canvas, the longer side at most ``limit``."""
    scale = min(1.0, limit / max(width, height, 1))
    return max(1, round(width * scale)), max(1, round(height * scale)), scale


def multiply_composite(
    background: bytes,
    width: int,
    height: int,
    rowstride: int,
    channels: int,
    layer: bytes,
    x: int,
    y: int,
    layer_width: int,
    layer_height: int,
    cover: bytes | None = None,
) -> bytes:
    """Multiply a straight-alpha RGBA u8 layer placed at (x, y) onto an 8-bit RGB/RGBA image.

    ``cover``: the cutout's u8 alpha (``width * height``) above the layer, hiding it.
    Returns packed RGB bytes (rowstride ``3 * width``).
    """
    out = bytearray(3 * width * height)
    for row in range(height):  # the background's RGB, by strided slices (C speed, not per pixel)
        src, j = row * rowstride, 3 * row * width
        line = background[src : src + width * channels]
        for c in range(3):
            out[j + c : j + 3 * width : 3] = line[c::channels]
    for ly in range(max(0, -y), min(layer_height, height - y)):
        base = 4 * ly * layer_width
        for lx in range(max(0, -x), min(layer_width, width - x)):
            k = base + 4 * lx
            a = layer[k + 3]
            if cover is not None:
                a = a * (255 - cover[(y + ly) * width + x + lx]) // 255
            if not a:
                continue
            j = 3 * ((y + ly) * width + x + lx)
            for c in range(3):
                factor = 1.0 - a * (255 - layer[k + c]) / 65025.0
                out[j + c] = min(255, max(0, math.floor(out[j + c] * factor + 0.5)))
    return bytes(out)


HORIZON_DASH = 6  # pixels on, pixels off
HORIZON_RGB = bytes((255, 140, 0))


def draw_horizon(rgb: bytes, width: int, height: int, row: float) -> bytes:
    """Packed RGB with the horizon drawn as a dashed orange line at ``row``; unchanged when it lies outside."""
    y = math.floor(row)
    if not 0 <= y < height:
        return rgb
    out = bytearray(rgb)
    for x in range(width):
        if (x // HORIZON_DASH) % 2 == 0:
            j = 3 * (y * width + x)
            out[j : j + 3] = HORIZON_RGB
    return bytes(out)
