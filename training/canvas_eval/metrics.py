"""Canvas-scale shadow metrics on the ground the viewer sees (docs/canvas_eval.md).

Every metric compares a predicted shadow ``p`` with the truth ``g`` (both s over the canvas, in [0, 1])
inside a boolean ``region``: :func:`ground_region`, the canvas pixels below the horizon outside the object's
mask dilated by one pixel. Filters are normalised convolutions restricted to the region, so the object's
pixels (where the ground behind it is hidden) never leak into the ground next to it.
"""

from __future__ import annotations

from typing import cast

import numpy as np
from scipy import ndimage
from skimage.metrics import structural_similarity

from training.metrics import zncc

SOLID = 0.5  # mask coverage above which a pixel is the object's
BAND_SIGMAS = (1.0, 4.0)  # the band-pass filter: a difference of Gaussians (pixels)
GRADIENT_SIGMA = 1.0  # smoothing before gradients (pixels)
DARK_QUANTILE = 99.9  # the darkness percentile compared
FOOT_SHARE = 0.03  # the object's feet: its solid pixels in the lowest 3 % of its height
CONTACT_RADIUS = 6.0  # the contact region reaches this far from the feet, in pixels at 768 rows
MIN_CONTACT_RADIUS = 2.0  # pixels, on small canvases: the dilated mask takes the first pixel
MIN_CONTACT = 0.05  # a contact region whose true mean shadow is below this has no contact shadow to score
SHADOW_LEVEL = 0.5  # IoU and the gap compare the regions where s is at least this
MIN_GAP = 4.0  # pixels: a truth whose shadow is nearer touches the object (the ground leaves out its 1-px rim)
NAMES = (
    "zncc",
    "dssim",
    "bandpass_zncc",
    "gradient_energy",
    "dark_ratio",
    "iou",
    "outline_distance",
    "gap_ratio",
    "contact_ratio",
)


def ground_region(mask: np.ndarray, horizon: float) -> np.ndarray:
    """The ground the viewer sees: pixel centres below the ``horizon`` row, outside the object's mask
    (coverage > 0) dilated by one pixel (8-neighbourhood). (H, W) bool."""
    covered = ndimage.binary_dilation(np.asarray(mask) > 0, structure=np.ones((3, 3), bool))
    rows = np.arange(mask.shape[0])[:, None] + 0.5
    return (rows > horizon) & np.logical_not(covered)


def masked_gaussian(image: np.ndarray, region: np.ndarray, sigma: float) -> np.ndarray:
    """Gaussian blur of ``image`` over ``region`` only (normalised convolution); 0 outside ``region``.
    Float32 (the filters are the metrics' main cost on a canvas)."""
    num = ndimage.gaussian_filter(np.where(region, image, 0.0).astype(np.float32), sigma, mode="nearest")
    den = ndimage.gaussian_filter(region.astype(np.float32), sigma, mode="nearest")
    return np.where(region & (den > 1e-6), num / np.maximum(den, 1e-6), 0.0).astype(np.float32)


def region_zncc(p: np.ndarray, g: np.ndarray, region: np.ndarray) -> float:
    """The conventions' ZNCC over the pixels of ``region``."""
    return zncc(np.asarray(p)[region], np.asarray(g)[region])


def region_dssim(p: np.ndarray, g: np.ndarray, region: np.ndarray) -> float:
    """(1 - SSIM) / 2 with SSIM's map (7 x 7 windows, data range 1) averaged over ``region``; both images are
    set to 0 outside it first."""
    a = np.where(region, p, 0.0).astype(np.float64)
    b = np.where(region, g, 0.0).astype(np.float64)
    ssim_map = cast("tuple[float, np.ndarray]", structural_similarity(a, b, data_range=1.0, full=True))[1]
    return float((1.0 - ssim_map[region].mean()) / 2.0)


def bandpass(image: np.ndarray, region: np.ndarray, sigmas: tuple[float, float] = BAND_SIGMAS) -> np.ndarray:
    """The difference of Gaussians G(sigma 1) - G(sigma 2) of ``image`` over ``region``."""
    return masked_gaussian(image, region, sigmas[0]) - masked_gaussian(image, region, sigmas[1])


def bandpass_zncc(p: np.ndarray, g: np.ndarray, region: np.ndarray) -> float:
    """ZNCC of both images' :func:`bandpass` over ``region``: do edges and penumbrae sit where they should."""
    return region_zncc(bandpass(p, region), bandpass(g, region), region)


def gradient_energy(image: np.ndarray, region: np.ndarray, sigma: float = GRADIENT_SIGMA) -> float:
    """sum |grad image|^2 over pixel pairs inside ``region`` after a Gaussian of ``sigma`` over ``region``."""
    smooth = masked_gaussian(image, region, sigma)
    dy = np.diff(smooth, axis=0)[region[1:] & region[:-1]].astype(np.float64)
    dx = np.diff(smooth, axis=1)[region[:, 1:] & region[:, :-1]].astype(np.float64)
    return float((dy * dy).sum() + (dx * dx).sum())


def gradient_energy_ratio(p: np.ndarray, g: np.ndarray, region: np.ndarray) -> float:
    """:func:`gradient_energy` of ``p`` over that of ``g``: below 1 too soft, above 1 too sharp (or noisy);
    nan when the truth has no gradient."""
    truth = gradient_energy(g, region)
    return gradient_energy(p, region) / truth if truth > 0 else float("nan")


def dark_ratio(p: np.ndarray, g: np.ndarray, region: np.ndarray, q: float = DARK_QUANTILE) -> float:
    """The ``q``-th percentile of ``p`` over that of ``g`` in ``region``: how dark the darkest shadow gets;
    nan when the truth's percentile is 0."""
    truth = float(np.percentile(g[region], q))
    return float(np.percentile(p[region], q)) / truth if truth > 0 else float("nan")


def shadow_iou(p: np.ndarray, g: np.ndarray, region: np.ndarray) -> float:
    """Intersection over union of the regions where ``p`` and ``g`` are at least ``SHADOW_LEVEL`` in ``region``
    (nan where neither reaches it)."""
    a, b = (p >= SHADOW_LEVEL) & region, (g >= SHADOW_LEVEL) & region
    union = int((a | b).sum())
    return int((a & b).sum()) / union if union else float("nan")


def outline_distance(p: np.ndarray, g: np.ndarray, region: np.ndarray) -> float:
    """The median distance (pixels) from each pixel of either shadow's outline (the region where it is at least
    ``SHADOW_LEVEL``, its pixels beside one that is not, within ``region``) to the other's outline: how far the
    shadow's edges lie from the truth's (nan where either has no outline)."""
    outlines = []
    for s in (p, g):
        dark = (s >= SHADOW_LEVEL) & region
        inner = np.asarray(ndimage.binary_erosion(dark, border_value=1), bool)
        outlines.append(dark & ~inner & region)
    if not outlines[0].any() or not outlines[1].any():
        return float("nan")
    to = [np.asarray(ndimage.distance_transform_edt(~o)) for o in outlines]
    return float(np.median(np.concatenate([to[1][outlines[0]], to[0][outlines[1]]])))


def shadow_gap(s: np.ndarray, mask: np.ndarray, region: np.ndarray) -> float:
    """The distance (pixels) from the object (its mask) to the nearest pixel of ``region`` where ``s`` is at
    least ``SHADOW_LEVEL``: how far a floating object's shadow lies from it (nan where there is none)."""
    dark = (s >= SHADOW_LEVEL) & region
    if not dark.any():
        return float("nan")
    distance = np.asarray(ndimage.distance_transform_edt(~(np.asarray(mask) > SOLID)))
    return float(distance[dark].min())


def gap_ratio(p: np.ndarray, g: np.ndarray, mask: np.ndarray, region: np.ndarray) -> float:
    """The predicted shadow's :func:`shadow_gap` over the truth's; nan where the truth's is under ``MIN_GAP``
    (its shadow touches the object: nothing floats)."""
    truth = shadow_gap(g, mask, region)
    return shadow_gap(p, mask, region) / truth if truth >= MIN_GAP else float("nan")


def contact_region(mask: np.ndarray, region: np.ndarray) -> np.ndarray:
    """Where the object meets the ground: pixels of ``region`` within ``CONTACT_RADIUS`` (scaled by the
    canvas height / 768, at least ``MIN_CONTACT_RADIUS``) of the object's feet, at or below the feet's top row.

    The feet are the solid pixels (coverage > ``SOLID``) in the lowest ``FOOT_SHARE`` of the object's height
    on the canvas (at least its lowest solid row).
    """
    solid = np.asarray(mask) > SOLID
    rows = np.flatnonzero(solid.any(axis=1))
    if rows.size == 0:
        return np.zeros_like(region)
    top, bottom = int(rows[0]), int(rows[-1])
    first_foot = bottom - int(FOOT_SHARE * (bottom - top + 1))
    feet = solid.copy()
    feet[:first_foot] = False
    radius = max(CONTACT_RADIUS * mask.shape[0] / 768, MIN_CONTACT_RADIUS)
    near = ndimage.distance_transform_edt(~feet) <= radius
    below = np.arange(mask.shape[0])[:, None] >= first_foot
    return region & near & below


def contact_ratio(p: np.ndarray, g: np.ndarray, contact: np.ndarray) -> float:
    """Mean ``p`` over mean ``g`` in the contact region; nan when it is empty or the truth is lighter there
    than ``MIN_CONTACT`` (the light leaves the contact lit)."""
    if not contact.any():
        return float("nan")
    truth = float(g[contact].mean())
    return float(p[contact].mean()) / truth if truth >= MIN_CONTACT else float("nan")


def score_case(p: np.ndarray, g: np.ndarray, mask: np.ndarray, horizon: float) -> dict[str, float]:
    """Every metric of ``NAMES`` for one case (prediction ``p``, truth ``g``, the object's ``mask`` and the
    canvas's true horizon row)."""
    p = np.asarray(p, np.float64)
    g = np.asarray(g, np.float64)
    if p.shape != g.shape or g.shape != mask.shape:
        raise ValueError(f"shapes differ: prediction {p.shape}, truth {g.shape}, mask {mask.shape}")
    region = ground_region(mask, horizon)
    return {
        "zncc": region_zncc(p, g, region),
        "dssim": region_dssim(p, g, region),
        "bandpass_zncc": bandpass_zncc(p, g, region),
        "gradient_energy": gradient_energy_ratio(p, g, region),
        "dark_ratio": dark_ratio(p, g, region),
        "iou": shadow_iou(p, g, region),
        "outline_distance": outline_distance(p, g, region),
        "gap_ratio": gap_ratio(p, g, mask, region),
        "contact_ratio": contact_ratio(p, g, contact_region(mask, region)),
    }


__all__ = [
    "NAMES",
    "bandpass",
    "bandpass_zncc",
    "contact_region",
    "contact_ratio",
    "dark_ratio",
    "gap_ratio",
    "gradient_energy",
    "gradient_energy_ratio",
    "ground_region",
    "masked_gaussian",
    "outline_distance",
    "shadow_gap",
    "shadow_iou",
    "region_dssim",
    "region_zncc",
    "score_case",
]
