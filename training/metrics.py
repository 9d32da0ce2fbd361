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
    return (1.0 - float(s)) / 2.0  # pyright: ignore[reportArgumentType]  (a float unless asked for gradients)


def all_metrics(p: np.ndarray, g: np.ndarray) -> dict[str, float]:
    """The four metrics of one predicted shadow ``p`` against the ground truth ``g`` (2D arrays)."""
    return {"RMSE": rmse(p, g), "RMSE-s": rmse_s(p, g), "ZNCC": zncc(p, g), "DSSIM": dssim(p, g)}


def mean_metrics(rows: list[dict[str, float]]) -> dict[str, float]:
    """Average per-image metrics."""
    return {k: float(np.mean([r[k] for r in rows])) for k in NAMES} if rows else {k: float("nan") for k in NAMES}


MIN_CAST = 30.0  # cast-shadow mass (full-shadow pixels) below which a shadow has no measurable direction


def contact_point(mask: np.ndarray) -> tuple[float, float]:
    """Where the object meets the ground in the frame: (x, y) at the bottom edge of its lowest solid row,
    in the middle of that row's solid pixels (continuous coordinates, pixel centres at k + 0.5)."""
    solid = mask > 0.5
    rows = np.flatnonzero(solid.any(axis=1))
    if rows.size == 0:
        raise ValueError("contact_point: the mask has no solid pixel")
    cols = np.flatnonzero(solid[rows[-1]])
    return float(cols.mean() + 0.5), float(rows[-1] + 1)


def cast_shadow(s: np.ndarray, mask: np.ndarray) -> np.ndarray:
    """The visible cast shadow: the shadow outside the object's silhouette."""
    return np.asarray(s, np.float64) * (1.0 - np.clip(mask, 0.0, 1.0))


def shadow_direction(s: np.ndarray, mask: np.ndarray) -> np.ndarray | None:
    """The vector (dx, dy) from the contact point to the cast shadow's centroid (frame pixels), or None when
    the cast shadow holds less than ``MIN_CAST``."""
    c = cast_shadow(s, mask)
    mass = c.sum()
    if mass < MIN_CAST:
        return None
    y, x = np.mgrid[: c.shape[0], : c.shape[1]] + 0.5
    x0, y0 = contact_point(mask)
    return np.array([(c * x).sum() / mass - x0, (c * y).sum() / mass - y0])


def shadow_extent(s: np.ndarray, mask: np.ndarray, direction: np.ndarray, quantile: float = 0.95) -> float:
    """How far the cast shadow reaches from the contact point along ``direction``: the shadow-weighted
    ``quantile`` of the pixels' distances along it (frame pixels; 0 without cast shadow)."""
    c = cast_shadow(s, mask).ravel()
    if c.sum() <= 0:
        return 0.0
    y, x = np.mgrid[: s.shape[0], : s.shape[1]] + 0.5
    x0, y0 = contact_point(mask)
    u = np.asarray(direction, np.float64) / max(float(np.hypot(*direction)), 1e-12)
    along = ((x - x0) * u[0] + (y - y0) * u[1]).ravel()
    order = np.argsort(along)
    cum = np.cumsum(c[order])
    return float(along[order][np.searchsorted(cum, quantile * cum[-1])])


def sun_geometry(p: np.ndarray, g: np.ndarray, mask: np.ndarray) -> dict[str, float] | None:
    """Direction error (degrees, between the contact-to-centroid vectors of the predicted and the true cast
    shadow) and length ratio (predicted / true extent along the true direction); None when the true cast
    shadow is too small to have a direction. A prediction without cast shadow scores 180 degrees, ratio 0."""
    true_dir = shadow_direction(g, mask)
    if true_dir is None:
        return None
    true_len = shadow_extent(g, mask, true_dir)
    if true_len <= 0:
        return None
    pred_dir = shadow_direction(p, mask)
    if pred_dir is None:
        return {"direction_error": 180.0, "length_ratio": 0.0}
    cos = float(pred_dir @ true_dir) / max(float(np.hypot(*pred_dir) * np.hypot(*true_dir)), 1e-12)
    return {
        "direction_error": float(np.degrees(np.arccos(np.clip(cos, -1.0, 1.0)))),
        "length_ratio": shadow_extent(p, mask, true_dir) / true_len,
    }
