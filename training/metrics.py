"""The conventions' shadow metrics (per image; average over images yourself): RMSE, RMSE-s, ZNCC, DSSIM."""

from __future__ import annotations

import numpy as np
from skimage.metrics import structural_similarity

NAMES = ("RMSE", "RMSE-s", "ZNCC", "DSSIM")


def rmse(p: np.ndarray, g: np.ndarray) -> float:
    """sqrt(mean((p - g)^2))."""
    d = np.asarray(p, np.float64) - np.asarray(g, np.float64)
    return float(np.sqrt(np.mean(d * d)))


def rmse_s(p: np.ndarray, g: np.ndarray) -> float:
    """min over scalar k of sqrt(mean((k p - g)^2)); k = <p, g> / <p, p> in closed form (k = 0 when p = 0)."""
    p = np.asarray(p, np.float64).ravel()
    g = np.asarray(g, np.float64).ravel()
    pp = float(p @ p)
    k = float(p @ g) / pp if pp > 0 else 0.0
    d = k * p - g
    return float(np.sqrt(np.mean(d * d)))


def zncc(p: np.ndarray, g: np.ndarray) -> float:
    """mean((p - mean p)(g - mean g)) / (std p std g); if either image is constant: 1 if p == g everywhere, else 0."""
    p = np.asarray(p, np.float64)
    g = np.asarray(g, np.float64)
    sp, sg = p.std(), g.std()
    if sp == 0 or sg == 0:
        return 1.0 if np.array_equal(p, g) else 0.0
    return float(np.mean((p - p.mean()) * (g - g.mean())) / (sp * sg))


def dssim(p: np.ndarray, g: np.ndarray) -> float:
    """(1 - SSIM(p, g)) / 2 with skimage's structural_similarity, data_range = 1."""
    s = structural_similarity(np.asarray(p, np.float64), np.asarray(g, np.float64), data_range=1.0)
    return float((1.0 - s) / 2.0)


def all_metrics(p: np.ndarray, g: np.ndarray) -> dict[str, float]:
    """The four metrics of one predicted shadow ``p`` against the ground truth ``g`` (2D arrays)."""
    return {"RMSE": rmse(p, g), "RMSE-s": rmse_s(p, g), "ZNCC": zncc(p, g), "DSSIM": dssim(p, g)}


def mean_metrics(rows: list[dict[str, float]]) -> dict[str, float]:
    """Average per-image metrics."""
    return {k: float(np.mean([r[k] for r in rows])) for k in NAMES} if rows else {k: float("nan") for k in NAMES}
