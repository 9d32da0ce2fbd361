"""The light map drawn for the editor (pure Python: the engine's Gaussians, tone-mapped).

Same picture as the worker's ``elm_image``: each light is
``intensity * exp(-d^2 / (2 softness))`` with the editor model's wrapped
distance, tone-mapped ``v / (1 + v)`` from night blue to warm white.
"""

from __future__ import annotations

import math
from typing import Any

NIGHT = (0.10, 0.13, 0.20)
LIGHT = (1.0, 0.96, 0.85)


def map_values(light_map: Any, width: int, height: int) -> list[list[float]]:
    """Radiance at the centres of a width x height grid (u across, v down)."""
    rows = [[0.0] * width for _ in range(height)]
    for light in light_map:
        two_s = 2.0 * light.softness
        cols = []
        for j in range(width):
            du = abs((j + 0.5) / width - light.u) % 1.0
            du = min(du, 1.0 - du)
            cols.append(math.exp(-((2.0 * du) ** 2) / two_s))
        for i in range(height):
            f = light.intensity * math.exp(-(((i + 0.5) / height - light.v) ** 2) / two_s)
            if f < 1e-6:
                continue
            row = rows[i]
            for j in range(width):
                row[j] += f * cols[j]
    return rows


def map_rgb(light_map: Any, width: int = 96, height: int = 48) -> bytes:
    """RGB888 bytes (height x width x 3) of the tone-mapped light map."""
    lut = bytes(
        round(255 * (n + (b - n) * k / 255)) for k in range(256) for n, b in zip(NIGHT, LIGHT, strict=True)
    )  # 256 entries x 3 channels
    out = bytearray(width * height * 3)
    p = 0
    for row in map_values(light_map, width, height):
        for v in row:
            k = 3 * int(255 * v / (1.0 + v) + 0.5)
            out[p : p + 3] = lut[k : k + 3]
            p += 3
    return bytes(out)
