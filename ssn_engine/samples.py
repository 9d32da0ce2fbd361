"""Sample inputs drawn by the project itself: a shaded pawn cutout and a studio backdrop."""

from __future__ import annotations

import numpy as np

SAMPLE_SIZE = (1200, 900)  # width, height of the sample canvas
SAMPLE_FILES = ("sample_cutout.png", "sample_background.png")  # what demo --save-samples writes
STRIPE_ROWS = 64  # canvas rows of the pawn shaded at once


def _pawn_profile(t: np.ndarray) -> np.ndarray:
    """Radius of the pawn (in units of its height) at height t in [0, 1] from its base."""
    smooth = lambda a, b, x: np.clip((x - a) / (b - a), 0, 1) ** 2 * (3 - 2 * np.clip((x - a) / (b - a), 0, 1))
    r = 0.30 - 0.08 * smooth(0.05, 0.13, t)
    r = np.where(t > 0.13, 0.21 - 0.11 * smooth(0.13, 0.55, t) ** 0.7, r)
    r = np.where((t > 0.53) & (t <= 0.60), 0.17, r)
    r = np.where((t > 0.60) & (t <= 0.66), 0.09, r)
    head = np.sqrt(np.clip(0.18**2 - (t - 0.82) ** 2, 0, None))
    r = np.where(t > 0.66, head, r)
    return np.where((t < 0) | (t > 1), 0.0, r)


def pawn_cutout(size: tuple[int, int] = SAMPLE_SIZE, height: int = 560, base_y: int = 800) -> np.ndarray:
    """A shaded terracotta pawn on a transparent canvas, RGBA uint8 (H, W, 4)."""
    w, h = size
    ss = 2  # supersampling for antialiased edges
    # Only the pawn's box is computed (its radius is at most 0.3 heights): the rest of the canvas is transparent.
    x0, x1 = max(0, int(w / 2 - 0.31 * height) - 1), min(w, int(w / 2 + 0.31 * height) + 2)
    y0, y1 = max(0, base_y - height - 1), min(h, base_y + 1)
    out = np.zeros((h, w, 4), np.uint8)
    for top in range(y0, y1, STRIPE_ROWS):  # in stripes: the float64 shading of the whole box would peak ~140 MB
        bottom = min(top + STRIPE_ROWS, y1)
        out[top:bottom, x0:x1] = _shaded_pawn(x0, x1, top, bottom, ss, w, height, base_y)
    return out


def _shaded_pawn(x0: int, x1: int, y0: int, y1: int, ss: int, w: int, height: int, base_y: int) -> np.ndarray:
    """The pawn's RGBA uint8 pixels on canvas rows [y0, y1) and columns [x0, x1)."""
    h, w_box = y1 - y0, x1 - x0
    ys, xs = np.mgrid[y0 * ss : y1 * ss, x0 * ss : x1 * ss].astype(np.float64)
    t = (base_y - (ys + 0.5) / ss) / height
    x = ((xs + 0.5) / ss - w / 2) / height
    r = _pawn_profile(t)
    dr = np.gradient(_pawn_profile(np.linspace(0, 1, 2001)), 1 / 2000)
    drdt = np.interp(t, np.linspace(0, 1, 2001), dr)
    inside = np.abs(x) < r
    sin_phi = np.where(inside, x / np.maximum(r, 1e-9), 0)
    cos_phi = np.sqrt(np.clip(1 - sin_phi**2, 0, 1))
    n = np.stack([sin_phi, -drdt, cos_phi], -1)
    n /= np.linalg.norm(n, axis=-1, keepdims=True)
    light = np.array([-0.5, 0.55, 0.67])
    light /= np.linalg.norm(light)
    diffuse = np.clip(n @ light, 0, None)
    half = light + np.array([0, 0, 1.0])
    spec = np.clip(n @ (half / np.linalg.norm(half)), 0, None) ** 40
    albedo = np.array([0.80, 0.36, 0.24])
    rgb = albedo * (0.22 + 0.78 * diffuse[..., None]) + 0.35 * spec[..., None]
    rgba = np.concatenate([np.clip(rgb, 0, 1), inside[..., None].astype(np.float64)], -1)
    rgba = rgba.reshape(h, ss, w_box, ss, 4).mean(axis=(1, 3))
    rgba[..., :3] = np.where(rgba[..., 3:] > 0, rgba[..., :3] / np.maximum(rgba[..., 3:], 1e-9), 0)
    return np.rint(rgba * 255).astype(np.uint8)


def studio_background(size: tuple[int, int] = SAMPLE_SIZE, horizon_y: int = 520) -> np.ndarray:
    """A warm studio backdrop: a wall above a softly lit floor, RGB uint8 (H, W, 3)."""
    w, h = size
    y = np.arange(h, dtype=np.float64)[:, None, None]
    x = np.arange(w, dtype=np.float64)[None, :, None]
    wall = np.array([0.80, 0.78, 0.74]) - 0.10 * (1 - y / horizon_y)
    floor = np.array([0.93, 0.90, 0.85]) - 0.12 * ((y - horizon_y) / (h - horizon_y))
    blend = np.clip((y - horizon_y) / 40 + 0.5, 0, 1)
    rgb = wall * (1 - blend) + floor * blend
    vignette = 1 - 0.12 * ((x - w / 2) / (w / 2)) ** 2
    return np.rint(np.clip(rgb * vignette, 0, 1) * 255).astype(np.uint8)
