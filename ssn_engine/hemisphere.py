"""The upper-hemisphere texel grid of an ELM, and light maps rendered onto it.

Geometry follows ``docs/conventions.md``: an ELM has shape (H, 2H);
row i spans elevations 90 (1 - i/H) .. 90 (1 - (i+1)/H) degrees, column j
azimuths -180 + 360 j/W .. -180 + 360 (j+1)/W degrees from the camera's
horizontal forward direction, positive to its right.

Directions are returned in the *camera basis*: components along the camera's
right vector r, the world up y, and its horizontal forward vector f, so
``w = cos(e) sin(a) r + sin(e) y + cos(e) cos(a) f``.
"""

from __future__ import annotations

import functools

import numpy as np
from scipy.special import erf

from .host_kit.light_map import ASPECT, GaussianLight, LightMap, disk_samples, disk_texel_means
from .host_kit.sky_map import NETWORK_SHAPE


def texel_edges(h: int) -> tuple[np.ndarray, np.ndarray]:
    """Elevation edges (h + 1, descending from pi/2) and azimuth edges (2h + 1), radians."""
    elevation = np.pi / 2 * (1.0 - np.arange(h + 1) / h)
    azimuth = -np.pi + 2 * np.pi * np.arange(2 * h + 1) / (2 * h)
    return elevation, azimuth


def texel_weights(h: int) -> np.ndarray:
    """Cosine-weighted solid angle W_t of every texel, shape (h, 2h); they sum to pi."""
    elevation, azimuth = texel_edges(h)
    band = 0.5 * (np.sin(elevation[:-1]) ** 2 - np.sin(elevation[1:]) ** 2)
    return (band[:, None] * np.diff(azimuth)[None, :]).astype(np.float64)


CONCENTRATED_TEXELS = 16  # a small light's energy lies in this many brightest texels of the 16 x 32 ELM


def light_concentration(elms: np.ndarray) -> np.ndarray:
    """The share of each ELM's (n, h, 2h) light (radiance times W_t) in its ``CONCENTRATED_TEXELS`` brightest
    texels: near 1 for one or two small lights, about 0.1 for a broad sky; 0 for a dark map."""
    elms = np.maximum(np.asarray(elms, np.float64), 0.0)
    light = (elms * texel_weights(elms.shape[1])).reshape(len(elms), -1)
    top = -np.partition(-light, CONCENTRATED_TEXELS - 1, axis=1)[:, :CONCENTRATED_TEXELS]
    total = light.sum(axis=1)
    return np.where(total > 0, top.sum(axis=1) / np.maximum(total, 1e-300), 0.0)


def direction(elevation: np.ndarray, azimuth: np.ndarray) -> np.ndarray:
    """Unit vectors (..., 3) in the camera basis (right, up, forward)."""
    elevation, azimuth = np.broadcast_arrays(elevation, azimuth)
    ce = np.cos(elevation)
    return np.stack([ce * np.sin(azimuth), np.sin(elevation), ce * np.cos(azimuth)], axis=-1)


def texel_centres(h: int) -> np.ndarray:
    """Direction of each texel's centre, shape (h, 2h, 3), camera basis."""
    elevation, azimuth = texel_edges(h)
    e = 0.5 * (elevation[:-1] + elevation[1:])
    a = 0.5 * (azimuth[:-1] + azimuth[1:])
    return direction(e[:, None], a[None, :])


def stratified_directions(h: int, samples: int, rng: np.random.Generator | None = None) -> np.ndarray:
    """Cosine-distributed, stratified directions in every texel, jittered by ``rng`` (None: each stratum's
    centre).

    Returns (h, 2h, samples, 3) in the camera basis. ``samples`` must be a
    square (k x k strata in azimuth and sin^2(elevation)); each direction then
    carries the same share of the texel's cosine-weighted solid angle, so the
    texel's occlusion is the plain mean of the samples' hits.
    """
    k = int(round(np.sqrt(samples)))
    if k * k != samples:
        raise ValueError(f"samples must be a square number, got {samples}")
    elevation, azimuth = texel_edges(h)
    q_hi, q_lo = np.sin(elevation[:-1]) ** 2, np.sin(elevation[1:]) ** 2
    strata = np.arange(k)

    def jitter() -> np.ndarray | float:
        return 0.5 if rng is None else rng.random((h, 2 * h, k, k))

    sq = (strata[:, None] + jitter()) / k  # axis 2: sin^2(e) stratum
    sa = (strata[None, :] + jitter()) / k  # axis 3: azimuth stratum
    q = q_lo[:, None, None, None] + sq * (q_hi - q_lo)[:, None, None, None]
    a = azimuth[None, :-1, None, None] + sa * np.diff(azimuth)[None, :, None, None]
    e = np.arcsin(np.sqrt(np.clip(q, 0.0, 1.0)))
    return direction(e, a).reshape(h, 2 * h, samples, 3)


def render_light_maps(
    u: np.ndarray, v: np.ndarray, softness: np.ndarray, intensity: np.ndarray, h: int = NETWORK_SHAPE[0]
) -> np.ndarray:
    """Each texel's mean radiance under a batch of Gaussian mixtures, light ``k`` of map ``b`` given by
    ``u[b, k]``, ``v[b, k]``, ``softness[b, k]`` and ``intensity[b, k]`` (intensity 0: no light): (B, h, 2h)
    float32. The definition of :func:`ssn_engine.host_kit.sky_map.map_values` (separable erf integrals, the azimuth
    wrapping), vectorised."""
    u, v, softness, intensity = (np.asarray(a, np.float64) for a in (u, v, softness, intensity))
    edges = np.arange(2 * h + 1) / h  # x and y in map heights; x spans [0, 2)
    s = np.sqrt(2.0 * softness)[..., None]  # (B, K, 1)
    ex = np.zeros(u.shape + (2 * h,))
    for shift in (-ASPECT, 0.0, ASPECT):
        ex += np.diff(erf((edges - (ASPECT * u + shift)[..., None]) / s), axis=-1)
    ey = np.diff(erf((edges[: h + 1] - v[..., None]) / s), axis=-1)  # (B, K, h)
    weight = intensity * (np.pi / 2.0) * softness * h * h  # the texel means' norm, squared
    return np.einsum("bk,bky,bkx->byx", weight, ey, ex).astype(np.float32)


def render_light_map(light_map: LightMap, h: int = NETWORK_SHAPE[0]) -> np.ndarray:
    """Each texel's mean radiance under one light map, shape (h, 2h), float32: its Gaussians by
    :func:`render_light_maps`, its disk lights' power spread over the texels their directions fall in
    (:func:`ssn_engine.host_kit.light_map.disk_texel_means`), as :func:`ssn_engine.host_kit.sky_map.map_values`."""
    gaussians = [(g.u, g.v, g.softness, g.intensity) for g in light_map if g.angle is None]
    u, v, softness, intensity = (
        np.array([column]) for column in zip(*(gaussians or [(0.5, 0.5, 0.01, 0.0)]), strict=True)
    )
    out = render_light_maps(u, v, softness, intensity, h)[0]
    for light in light_map:
        if light.angle is not None:
            _add_disk(out, light)
    return out


def _add_disk(out: np.ndarray, light: GaussianLight) -> None:
    """Add a disk light's texel means to the map ``out`` (h, 2h) in place."""
    h, w = out.shape
    for (i, j), value in disk_texel_means(light, w, h, disk_samples(light.angle or 0.0, w)).items():
        out[i, j] += value


def light_power(light_map: LightMap, h: int = NETWORK_SHAPE[0]) -> np.ndarray:
    """Each light's unoccluded irradiance of the ground E0_i = sum_t L_t W_t (conventions, "Shadow value") on
    the (h, 2h) texel grid, shape (lights,): the shares in which their shadows add up."""
    return np.array([_light_power(light, h) for light in light_map])


@functools.lru_cache(maxsize=64)  # a light kept while the artist drags a lift or changes another light
def _light_power(light: GaussianLight, h: int) -> float:
    """One light's E0 (:func:`light_power`)."""
    return float((render_light_map(LightMap([light]), h) * texel_weights(h)).sum())


def network_elm(elm: np.ndarray) -> np.ndarray:
    """Normalise ELMs (..., H, W) to the network's input scale: peak 1 per map.

    The shadow does not depend on the ELM's overall intensity, so the network
    sees every ELM scaled to a peak of 1 (all-zero maps stay zero).
    """
    elm = np.asarray(elm, np.float32)
    peak = elm.max(axis=(-2, -1), keepdims=True)
    return np.where(peak > 0, elm / np.where(peak > 0, peak, 1.0), 0.0).astype(np.float32)


def soft_shadow(occlusion: np.ndarray, elm: np.ndarray) -> np.ndarray:
    """The shadow s from per-texel occlusion maps and an ELM on the same grid.

    ``occlusion`` has shape (H, W, ...) (occ_t per texel, values in [0, 1]),
    ``elm`` shape (H, W). Returns s = sum_t L_t W_t occ_t / sum_t L_t W_t,
    all zeros for an all-zero ELM.
    """
    h, w = elm.shape
    if occlusion.shape[:2] != (h, w):
        raise ValueError(f"occlusion grid {occlusion.shape[:2]} does not match ELM {elm.shape}")
    weights = np.asarray(elm, np.float64) * texel_weights(h)
    total = weights.sum()
    if total <= 0:
        return np.zeros(occlusion.shape[2:], np.float32)
    s = np.tensordot(weights / total, occlusion, axes=([0, 1], [0, 1]))
    return np.clip(s, 0.0, 1.0).astype(np.float32)
