"""The light map rasterised onto the sky map's texel grid (stdlib only): the ELM's shape and the definition of
each texel's value.

An ELM (conventions, "Environment light map") is an (H, 2H) grid over the upper hemisphere, row 0 at the
zenith, u across (the azimuth, wrapping around) and v down. Under a light map (a sum of 2D Gaussians in map
coordinates, or uniform disks with an ``angle``) each texel holds its *mean* radiance over its area: per Gaussian,
the product of two separable erf integrals, across over the light and its copies one map width left and right
(the azimuth wraps), down over the light alone; a disk's power spread over the texels its directions fall in
(:func:`ssn_engine.host_kit.light_map.disk_texel_means`). A light much smaller than a texel so keeps its energy
at any resolution.

:func:`map_values` is the definition, in the standard library for the hosts' pictures of the map;
:func:`ssn_engine.hemisphere.render_light_maps` is the same formula vectorised over batches with numpy (the
engine's and training's ELMs), tested equal to it.
"""

from __future__ import annotations

import math

from .light_map import ASPECT, LightMap, disk_samples, disk_texel_means

__all__ = ["NETWORK_SHAPE", "check_elm_shape", "map_values", "texel_means"]

NETWORK_SHAPE = (16, 32)  # the ELM the network takes: (H, W), W = 2H


def check_elm_shape(shape: tuple[int, ...], count: int) -> None:
    """ValueError unless ``shape`` is that of ``count`` network ELMs, (count, 16, 32)."""
    if tuple(shape) != (count, *NETWORK_SHAPE):
        raise ValueError(f"elms: expected shape ({count}, {NETWORK_SHAPE[0]}, {NETWORK_SHAPE[1]}), got {tuple(shape)}")


def texel_means(centre: float, sigma2: float, count: int, scale: float, shifts: tuple[float, ...]) -> list[float]:
    """Means over ``count`` texels of width ``1 / scale`` (map heights, the first starting at 0) of
    ``exp(-(x - centre)^2 / (2 sigma2))`` and its copies at ``shifts``."""
    s = math.sqrt(2.0 * sigma2)
    norm = math.sqrt(math.pi / 2.0) * math.sqrt(sigma2) * scale
    edges = [[math.erf((k / scale - centre - shift) / s) for k in range(count + 1)] for shift in shifts]
    return [norm * sum(e[k + 1] - e[k] for e in edges) for k in range(count)]


def map_values(lights: LightMap, width: int, height: int, cutoff: float = 0.0) -> list[list[float]]:
    """Each texel's mean radiance on a ``width`` x ``height`` grid (u across, v down). A light's rows and columns
    whose factor is below ``cutoff`` are left out (a picture's shortcut; 0: every texel, the exact map)."""
    rows = [[0.0] * width for _ in range(height)]
    for light in lights:
        if light.intensity <= 0:
            continue
        if light.angle is not None:  # a disk: its power spread over the texels its directions fall in
            for (i, j), value in disk_texel_means(light, width, height, disk_samples(light.angle, width)).items():
                rows[i][j] += value
            continue
        ex = texel_means(ASPECT * light.u, light.softness, width, height, (-ASPECT, 0.0, ASPECT))
        cols = [(j, f) for j, f in enumerate(ex) if f >= cutoff]
        ey = texel_means(light.v, light.softness, height, height, (0.0,))
        for i, g in enumerate(ey):
            g *= light.intensity
            if g < cutoff:
                continue
            row = rows[i]
            for j, f in cols:
                row[j] += g * f
    return rows
