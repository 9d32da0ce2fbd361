"""Brute-force ray casting (numpy, Moller-Trumbore against every triangle): the reference renderer.

Slow but independent of the scan-conversion renderer; tests and the
benchmark compare the two at sampled pixels.
"""

from __future__ import annotations

import numpy as np


def ray_distances(
    origins: np.ndarray, directions: np.ndarray, vertices: np.ndarray, faces: np.ndarray, eps: float = 1e-12
) -> np.ndarray:
    """The smallest t > 0 at which each ray origins[k] + t directions[k] meets a triangle: (K,), inf where none."""
    a = vertices[faces[:, 0]]
    e1 = vertices[faces[:, 1]] - a
    e2 = vertices[faces[:, 2]] - a
    nearest = np.full(len(origins), np.inf)
    for start in range(0, len(origins), 256):
        o = origins[start : start + 256, None, :]
        d = directions[start : start + 256, None, :]
        p = np.cross(d, e2)
        det = np.einsum("kfi,fi->kf", p, e1)
        ok = np.abs(det) > eps
        inv = np.where(ok, 1.0 / np.where(ok, det, 1.0), 0.0)
        s = o - a
        u = np.einsum("kfi,kfi->kf", s, p) * inv
        q = np.cross(s, e1)
        v = np.einsum("kfi,kfi->kf", d, q) * inv
        t = np.einsum("fi,kfi->kf", e2, q) * inv
        inside = ok & (u >= 0) & (v >= 0) & (u + v <= 1) & (t > 0)
        nearest[start : start + 256] = np.where(inside, t, np.inf).min(axis=1)
    return nearest


def ray_hits(
    origins: np.ndarray, directions: np.ndarray, vertices: np.ndarray, faces: np.ndarray, eps: float = 1e-12
) -> np.ndarray:
    """Whether each ray origins[k] + t directions[k], t > 0, hits any triangle: (K,) bool."""
    return np.isfinite(ray_distances(origins, directions, vertices, faces, eps))
