"""Random light maps of the paper's Table 1, sampled and rendered in batches with numpy.

The rendering is the vectorised form of :func:`ssn_engine.hemisphere.render_light_map`
(exact texel means of Gaussians via separable erf integrals, azimuth wrapping);
``tests/training/test_train_elm.py`` checks that the two agree.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from scipy.special import erf

from ssn_engine.light_map import ASPECT, INTENSITY_RANGE, MAX_LIGHTS, SOFTNESS_RANGE, GaussianLight, LightMap


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
        return LightMap([GaussianLight(float(self.u[b, i]), float(self.v[b, i]), float(self.softness[b, i]),
                                       float(self.intensity[b, i])) for i in k])


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


def render_lights(lights: LightBatch, h: int) -> np.ndarray:
    """Texel-mean radiance of every light map on an (h, 2h) grid: (B, h, 2h) float32."""
    edges = np.arange(2 * h + 1) / h
    s = np.sqrt(2.0 * lights.softness)[..., None]  # (B, K, 1)
    ex = np.zeros(lights.u.shape + (2 * h,))
    for shift in (-ASPECT, 0.0, ASPECT):
        c = (ASPECT * lights.u + shift)[..., None]
        ex += np.diff(erf((edges - c) / s), axis=-1)
    ey = np.diff(erf((edges[: h + 1] - lights.v[..., None]) / s), axis=-1)  # (B, K, h)
    norm2 = (np.pi / 2.0) * lights.softness * h * h
    weight = lights.intensity * norm2
    out = np.einsum("bk,bky,bkx->byx", weight, ey, ex)
    return out.astype(np.float32)
