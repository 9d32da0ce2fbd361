"""A proxy with depth: the cutout as the volume seen through its pixels between a near and a far surface.

Each covered pixel holds two pixel heights (the rows from the nearest and the
farthest surface point on its ray down to the image of that point's foot on
the ground, as in Sheng et al.'s pixel-height work); with a camera they give
the two depths along the pixel's ray (:func:`depth_from_heights`), and the
proxy is every point of that ray between them. A ground point is in a
direction's hard shadow when its ray towards the light passes through the
proxy (:func:`proxy_occlusion`), which is exact for the volume and needs no
mesh: every ray's image is a straight path towards the light's vanishing
point, clipped to the proxy's bounding box and sampled about twice a pixel.
"""

from __future__ import annotations

from collections.abc import Callable

import numpy as np

from ..camera import Camera, focal_from_fov
from ..frames import resample_frames
from .base import HORIZON_REACH
from .geometric import GeometricCard, _Card

STEPS_PER_PIXEL = 2.0  # samples per pixel of a ray's path through the proxy's box
CHUNK = 1 << 21  # ray samples evaluated at once (bounds memory)
FOV_RANGE = (15.0, 100.0)  # degrees: an estimated camera's field of view is kept inside


def depth_from_heights(camera: Camera, heights: np.ndarray, covered: np.ndarray) -> np.ndarray:
    """The depth (along the view axis) on each covered pixel's ray of the point whose foot lies ``heights``
    rows below the pixel centre; inf where the pixel is not covered or no point of its ray has that foot."""
    n = camera.n
    centres = np.arange(n) + 0.5
    cx = (centres - 0.5 * n) / camera.focal
    cy = -(centres - camera.shift - 0.5 * n) / camera.focal
    v, u, c = camera.view, camera.up, camera.centre
    # ray(col, row) = view + cx right + cy up; the foot of centre + d ray projects to the row k below
    a1 = cx[None, :] * 0.0 + (v[0] * u[0] + v[2] * u[2]) + cy[:, None] * (u[0] * u[0] + u[2] * u[2])
    a2 = cx[None, :] * 0.0 + (v[0] * v[0] + v[2] * v[2]) + cy[:, None] * (u[0] * v[0] + u[2] * v[2])
    target = centres[:, None] + heights
    k = (0.5 * n + camera.shift - target) / camera.focal
    den = a1 - k * a2
    d = (c[1] * u[1] - k * c[1] * v[1]) / np.where(np.abs(den) > 1e-12, den, 1e-12)
    ok = covered & (d > 0) & np.isfinite(d)
    return np.where(ok, d, np.inf).astype(np.float32)


def _box_interval(a: np.ndarray, b: np.ndarray, lo: np.ndarray, hi: np.ndarray) -> None:
    """Narrow [lo, hi] to where a + b t >= 0 (in place)."""
    with np.errstate(divide="ignore", invalid="ignore"):
        root = -a / b
    lo[:] = np.where(b > 0, np.maximum(lo, root), lo)
    hi[:] = np.where(b < 0, np.minimum(hi, root), hi)
    empty = (b == 0) & (a < 0)
    hi[empty] = -np.inf


def _image(t: np.ndarray, ray: tuple, half: float, shift: float, focal: float) -> tuple[np.ndarray, ...]:
    """Image column, row and depth of ray points at parameters ``t``; ``ray``: the start's depth, up and right
    coordinates relative to the camera and the direction's (d0, u0, x0, dv, du, dx)."""
    d0, u0, x0, dv, du, dx = ray
    depth = d0 + t * dv
    return half + focal * (x0 + t * dx) / depth, half + shift - focal * (u0 + t * du) / depth, depth


def proxy_occlusion(
    camera: Camera, front: np.ndarray, back: np.ndarray, directions: np.ndarray, ground: np.ndarray, top: float
) -> np.ndarray:
    """Hard-shadow occlusion (T, P) of the proxy (depths ``front`` <= ``back``, (m, m), inf / -inf where not
    covered; ``camera`` of size m) for world directions (T, 3) at ground points (P, 3); ``top``: the proxy's
    highest point above the ground."""
    m = front.shape[0]
    out = np.zeros((len(directions), len(ground)), np.float32)
    covered = np.isfinite(front)
    rows, cols = np.flatnonzero(covered.any(axis=1)), np.flatnonzero(covered.any(axis=0))
    if rows.size == 0:
        return out
    r0, r1, c0, c1 = float(rows[0]), float(rows[-1] + 1), float(cols[0]), float(cols[-1] + 1)
    half, f, shift = 0.5 * m, float(camera.focal), float(camera.shift)
    rel = (ground - camera.centre).astype(np.float64)
    v, u = camera.view.astype(np.float64), camera.up.astype(np.float64)
    d0, u0, x0 = rel @ v, rel @ u, rel[:, 0]
    flat_front = np.where(covered, front, np.inf).ravel()
    flat_back = np.where(covered, back, -np.inf).ravel()
    for k, w in enumerate(np.asarray(directions, np.float64)):
        if w[1] <= 1e-6:
            continue
        dv, du, dx = float(w @ v), float(w @ u), float(w[0])
        lo = np.zeros(len(ground))
        hi = np.maximum((top - ground[:, 1]) / w[1], 0.0)
        # inside the box's columns and rows (depth > 0 makes each bound linear in t), in front of the camera
        _box_interval((half - c0) * d0 + f * x0, (half - c0) * dv + f * dx, lo, hi)
        _box_interval((c1 - half) * d0 - f * x0, (c1 - half) * dv - f * dx, lo, hi)
        _box_interval((half + shift - r0) * d0 - f * u0, (half + shift - r0) * dv - f * du, lo, hi)
        _box_interval((r1 - half - shift) * d0 + f * u0, (r1 - half - shift) * dv + f * du, lo, hi)
        _box_interval(d0 - 1e-6, np.full_like(d0, dv), lo, hi)
        live = np.flatnonzero(hi > lo)
        if live.size == 0:
            continue
        t_lo, t_hi = lo[live], hi[live]
        ray = (d0[live], u0[live], x0[live], dv, du, dx)
        ca, ra, _ = _image(t_lo, ray, half, shift, f)
        cb, rb, _ = _image(t_hi, ray, half, shift, f)
        steps = np.maximum(np.ceil(STEPS_PER_PIXEL * np.hypot(cb - ca, rb - ra)), 1).astype(np.int64) + 1
        # rays grouped by their number of samples (powers of two), so each group is one dense array
        bucket = np.ceil(np.log2(steps)).astype(np.int64)
        hit = np.zeros(live.size, bool)
        for b in np.unique(bucket):
            sel = np.flatnonzero(bucket == b)
            s = 1 << int(b)
            frac = (np.arange(s) + 0.5) / s
            per = max(1, CHUNK // s)
            for i in range(0, sel.size, per):
                part = sel[i : i + per]
                t = t_lo[part, None] + (t_hi[part] - t_lo[part])[:, None] * frac[None, :]
                sub = (ray[0][part, None], ray[1][part, None], ray[2][part, None], dv, du, dx)
                col, row, depth = _image(t, sub, half, shift, f)
                j = np.clip(np.floor(col), 0, m - 1).astype(np.intp)
                ii = np.clip(np.floor(row), 0, m - 1).astype(np.intp)
                idx = ii * m + j
                hit[part] = ((flat_front[idx] <= depth) & (depth <= flat_back[idx])).any(axis=1)
        out[k, live[hit]] = 1.0
    return out


class ProxyCard(_Card):
    """The card's machinery (each texel's hard shadow traced when a light first needs it, the wider grid of long
    shadows) over the proxy's geometry: ``heights`` (2, m, m), the near and far pixel heights of the mask's
    pixels, placed with the card's camera (the camera input, or the default)."""

    def __init__(
        self,
        mask: np.ndarray,
        heights: np.ndarray,
        directions: np.ndarray,
        area_directions: np.ndarray,
        weights: np.ndarray,
        camera: tuple[float, float] | None = None,
    ) -> None:
        super().__init__(mask, directions, area_directions, weights, camera)
        if self.empty:
            return
        covered = mask > 0.5
        front = depth_from_heights(self.camera, heights[0], covered)
        back = depth_from_heights(self.camera, np.maximum(heights[1], 0.0), covered)
        self.front = front
        self.back = np.where(np.isfinite(front), np.maximum(np.where(np.isfinite(back), back, front), front), -np.inf)
        seen = np.isfinite(front)
        if not seen.any():
            self.empty = True
            return
        points = self.camera.centre + np.where(seen, front, 0.0)[..., None] * self.camera.pixel_rays()
        self.top = float(points[..., 1][seen].max()) * 1.001 + 1e-3

    def occlusion(self, directions: np.ndarray, ground: np.ndarray | None = None) -> np.ndarray:
        return proxy_occlusion(
            self.camera, self.front, self.back, directions, self.ground if ground is None else ground, self.top
        )


class HeightProxy(GeometricCard):
    """The proxy in the card's place: ``predict`` maps masks (b, 1, R, R) at the network's resolution R to
    :class:`training.model.unet.HeightNet`'s four maps (b, 4, R, R) in units of R (near and far pixel heights,
    horizon row, focal length). Hard shadows are traced on an ``internal`` grid, coarser than R (a texel costs
    about the square of it), and :meth:`card_shadows` returns them at R. Without a camera input the camera is
    the network's estimate: the means of its horizon and focal maps over the mask."""

    name = "proxy"

    def __init__(
        self, predict: Callable[[np.ndarray], np.ndarray], network: int, resolution: int = 256, internal: int = 64
    ) -> None:
        super().__init__(resolution, internal)
        self.predict, self.network = predict, network

    def _build(self, mask: np.ndarray, camera: tuple[float, float] | None) -> _Card:
        r, m = self.network, self.internal
        small = resample_frames(mask[None], r)
        maps = self.predict(small[:, None])[0].astype(np.float32) * r  # pixels of R
        covered = small[0] > 0.5
        if camera is None and covered.any():
            # the estimate, kept to fields of view a photograph has and horizons the card's pitches can reach
            lo, hi = focal_from_fov(r, FOV_RANGE[1]), focal_from_fov(r, FOV_RANGE[0])
            focal = float(np.clip(maps[3][covered].mean(), lo, hi))
            horizon = float(np.clip(maps[2][covered].mean(), -HORIZON_REACH * r, (1 + HORIZON_REACH) * r))
            internal_camera = (horizon * m / r, focal * m / r)
        elif camera is not None:
            scale = m / mask.shape[0]
            internal_camera = (camera[0] * scale, camera[1] * scale)
        else:
            internal_camera = None
        heights = resample_frames(maps[:2], m) * (m / r)
        return ProxyCard(
            resample_frames(mask[None], m)[0], heights, self._dirs, self._area_dirs, self._weights, internal_camera
        )

    def card_shadows(self, masks: np.ndarray, elms: np.ndarray, cameras: np.ndarray | None = None) -> np.ndarray:
        """The proxy's shadows (n, R, R) at the network's resolution."""
        return resample_frames(super().card_shadows(masks, elms, cameras), self.network)
