"""Uniform disk lights (conventions, "Light size"): directions sampled in the disk and their light-map entry.

A disk light of apparent diameter ``angle`` degrees is a spherical cap of half-angle angle / 2 about its
centre direction, of uniform radiance. Its shadow is s = 1 - E / E0 with E the cosine-weighted integral of
the cap's visible directions: :func:`disk_directions` samples the cap uniformly in solid angle (stratified,
jittered, by the concentric map of the unit square onto the disk), and each direction is weighted by its
cosine to the zenith.
"""

from __future__ import annotations

import math

import numpy as np

from ssn_engine.hemisphere import direction
from ssn_engine.host_kit.light_map import FORMAT, SOFTNESS_RANGE, VERSION

SUN, HAZY, SOFTBOX = 0.53, 3.0, 12.0  # the evaluation's three light sizes (degrees)
SAMPLES = {SUN: 16, HAZY: 64, SOFTBOX: 256}  # stratified directions per size: a smooth penumbra at 1024 x 768


def samples_for(angle: float) -> int:
    """Directions sampled for a disk of ``angle`` degrees: the table's entry, else 16 per degree squared,
    between 16 and 256 (always a square number)."""
    if angle in SAMPLES:
        return SAMPLES[angle]
    k = int(np.clip(math.ceil(4 * angle), 4, 16))
    return k * k


def _concentric(a: np.ndarray, b: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Shirley and Chiu's area-preserving map of [0, 1)^2 onto the unit disk: (radius, angle)."""
    x, y = 2 * a - 1, 2 * b - 1
    wide = np.abs(x) > np.abs(y)
    safe_x = np.where(x == 0, 1.0, x)
    safe_y = np.where(y == 0, 1.0, y)
    r = np.where(wide, x, y)
    phi = np.where(wide, (np.pi / 4) * (y / safe_x), np.pi / 2 - (np.pi / 4) * (x / safe_y))
    return np.abs(r), np.where(r < 0, phi + np.pi, phi)


def disk_directions(
    elevation: float, azimuth: float, angle: float, samples: int, rng: np.random.Generator | None = None
) -> np.ndarray:
    """Directions uniformly covering a disk light's cap, stratified, in the camera basis (right, up, forward).

    Parameters
    ----------
    elevation, azimuth
        The disk's centre, degrees (conventions: azimuth from the camera's horizontal forward, positive right).
    angle
        Apparent diameter, degrees (> 0).
    samples
        A square number k * k: one direction per stratum of a k x k grid, mapped onto the cap by area.
    rng
        Jitter within each stratum; None puts each direction at its stratum's centre.

    Returns
    -------
    numpy.ndarray
        (samples, 3) unit vectors; each stands for the same solid angle of the cap.
    """
    if not angle > 0:
        raise ValueError(f"angle must be positive, got {angle!r}")
    k = int(round(math.sqrt(samples)))
    if k * k != samples:
        raise ValueError(f"samples must be a square number, got {samples}")
    grid = (np.stack(np.meshgrid(np.arange(k), np.arange(k), indexing="ij"), -1).reshape(-1, 2)).astype(float)
    jitter = np.full((samples, 2), 0.5) if rng is None else rng.random((samples, 2))
    strata = (grid + jitter) / k
    r, phi = _concentric(strata[:, 0], strata[:, 1])
    # A cap of half-angle rho: area fraction r^2 maps to 1 - cos(alpha) = r^2 (1 - cos rho).
    rho = math.radians(angle) / 2
    cos_a = 1.0 - r * r * (1.0 - math.cos(rho))
    sin_a = np.sqrt(np.clip(1.0 - cos_a * cos_a, 0.0, 1.0))
    centre = direction(np.radians(elevation), np.radians(azimuth))
    e, a = math.radians(elevation), math.radians(azimuth)
    east = np.array([math.cos(a), 0.0, -math.sin(a)])  # horizontal, perpendicular to the centre
    north = np.array([-math.sin(e) * math.sin(a), math.cos(e), -math.sin(e) * math.cos(a)])
    return cos_a[:, None] * centre + (sin_a * np.cos(phi))[:, None] * east + (sin_a * np.sin(phi))[:, None] * north


def equivalent_softness(angle: float) -> float:
    """The Gaussian softness a reader without ``angle`` uses for a disk of ``angle`` degrees.

    A uniform disk of diameter angle has a standard deviation of angle / 4 degrees along each axis; as a
    Gaussian on the map (sigma in map heights, 90 degrees of elevation each) that is sigma = angle / 360,
    softness = sigma^2, clamped to the reader's range (so 0.53 and 3 degrees both read as its smallest light).
    """
    return float(np.clip((angle / 360.0) ** 2, *SOFTNESS_RANGE))


def light_map_file(elevation: float, azimuth: float, angle: float, intensity: float = 1.0) -> dict:
    """The light-map file of one disk light, with ``angle`` and its :func:`equivalent_softness`."""
    light = {
        "u": ((azimuth + 180.0) / 360.0) % 1.0,
        "v": 1.0 - elevation / 90.0,
        "angle": angle,
        "softness": equivalent_softness(angle),
        "intensity": intensity,
    }
    return {"format": FORMAT, "version": VERSION, "lights": [light]}


__all__ = [
    "SAMPLES",
    "SUN",
    "HAZY",
    "SOFTBOX",
    "disk_directions",
    "equivalent_softness",
    "light_map_file",
    "samples_for",
]
