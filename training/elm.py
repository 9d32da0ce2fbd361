"""Random light maps, sampled and rendered in batches with numpy: the paper's Table 1 and the light families
an artist uses (one small sun, two small lights, a broad sky).

The rendering is the engine's (:func:`ssn_engine.hemisphere.render_light_maps`: exact texel means of Gaussians,
the definition in :mod:`ssn_engine.host_kit.sky_map`).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from ssn_engine.hemisphere import render_light_maps
from ssn_engine.host_kit.light_map import INTENSITY_RANGE, MAX_LIGHTS, SOFTNESS_RANGE, GaussianLight, LightMap


@dataclass
class LightBatch:
    """B light maps padded to ``MAX_LIGHTS`` lights; absent lights have intensity 0 and ``active`` False."""

    u: np.ndarray  # (B, K)
    v: np.ndarray
    softness: np.ndarray
    intensity: np.ndarray
    active: np.ndarray  # (B, K) bool

    def __len__(self) -> int:
        return self.u.shape[0]

    def light_map(self, b: int) -> LightMap:
        """Light map ``b`` as the engine's :class:`LightMap`."""
        k = np.flatnonzero(self.active[b])
        return LightMap(
            [
                GaussianLight(
                    float(self.u[b, i]), float(self.v[b, i]), float(self.softness[b, i]), float(self.intensity[b, i])
                )
                for i in k
            ]
        )


def sample_lights(rng: np.random.Generator, batch: int, max_lights: int = MAX_LIGHTS) -> LightBatch:
    """Table 1: K uniform in 1..max_lights, (u, v) uniform in [0, 1]^2, intensity in [0, 3], softness in (0, 0.1]."""
    k = rng.integers(1, max_lights + 1, size=batch)
    active = np.arange(max_lights)[None, :] < k[:, None]
    shape = (batch, max_lights)
    intensity = rng.uniform(*INTENSITY_RANGE, size=shape) * active
    return LightBatch(
        u=rng.random(shape),
        v=rng.random(shape),
        softness=rng.uniform(*SOFTNESS_RANGE, size=shape),
        intensity=intensity,
        active=active,
    )


FAMILIES = ("sun", "two", "sky", "table1")
SUN_SOFTNESS = (1e-4, 0.005)  # a small light: at most ~4 degrees of standard deviation
SUN_ELEVATION = (5.0, 80.0)  # degrees
SKY_LIGHTS = (3, 8)
SKY_SOFTNESS = (0.03, 0.1)
TRAIN_MIX = {"sun": 0.35, "two": 0.2, "sky": 0.15, "table1": 0.3}  # the training mixture of families


def _padded(u, v, softness, intensity, active, max_lights: int) -> LightBatch:
    """(B, k) light arrays padded to ``max_lights`` absent lights (intensity 0, a valid softness)."""
    width = ((0, 0), (0, max_lights - u.shape[1]))
    return LightBatch(
        u=np.pad(u, width),
        v=np.pad(v, width),
        softness=np.pad(softness, width, constant_values=SUN_SOFTNESS[1]),
        intensity=np.pad(intensity * active, width),
        active=np.pad(active, width),
    )


def sample_family(rng: np.random.Generator, batch: int, family: str, max_lights: int = MAX_LIGHTS) -> LightBatch:
    """Light maps of one family: ``sun`` (one light, softness <= 0.005, elevation 5 to 80 degrees, any
    azimuth), ``two`` (two such lights, intensities 0.5 to 3), ``sky`` (3 to 8 broad lights, softness 0.03 to
    0.1, anywhere) or ``table1`` (:func:`sample_lights`)."""
    if family == "table1":
        return sample_lights(rng, batch, max_lights)
    if family in ("sun", "two"):
        k = 1 if family == "sun" else 2
        elevation = rng.uniform(*SUN_ELEVATION, size=(batch, k))
        v = 1.0 - elevation / 90.0
        softness = rng.uniform(*SUN_SOFTNESS, size=(batch, k))
        intensity = np.ones((batch, k)) if k == 1 else rng.uniform(0.5, 3.0, size=(batch, k))
        active = np.ones((batch, k), bool)
    elif family == "sky":
        k = SKY_LIGHTS[1]
        active = np.arange(k)[None, :] < rng.integers(SKY_LIGHTS[0], SKY_LIGHTS[1] + 1, size=batch)[:, None]
        v = rng.random((batch, k))
        softness = rng.uniform(*SKY_SOFTNESS, size=(batch, k))
        intensity = rng.uniform(*INTENSITY_RANGE, size=(batch, k))
    else:
        raise ValueError(f"light family must be one of {', '.join(FAMILIES)}, got {family!r}")
    return _padded(rng.random((batch, k)), v, softness, intensity, active, max_lights)


def sample_mixture(
    rng: np.random.Generator, batch: int, mix: dict[str, float], max_lights: int = MAX_LIGHTS
) -> LightBatch:
    """Each light map from a family drawn with the probabilities ``mix`` (e.g. :data:`TRAIN_MIX`)."""
    names = list(mix)
    p = np.array([mix[f] for f in names], float)
    pick = rng.choice(len(names), size=batch, p=p / p.sum())
    out = sample_lights(rng, batch, max_lights)
    for j, family in enumerate(names):
        rows = np.flatnonzero(pick == j)
        if rows.size:
            part = sample_family(rng, rows.size, family, max_lights)
            for field in ("u", "v", "softness", "intensity", "active"):
                getattr(out, field)[rows] = getattr(part, field)
    return out


def render_lights(lights: LightBatch, h: int) -> np.ndarray:
    """Texel-mean radiance of every light map on an (h, 2h) grid: (B, h, 2h) float32."""
    return render_light_maps(lights.u, lights.v, lights.softness, lights.intensity, h)
