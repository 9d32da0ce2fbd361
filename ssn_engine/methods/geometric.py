"""The non-learned baseline: the cutout as a flat vertical card.

The mask is taken to be a card standing upright on the ground, facing the
camera of the conventions (45 degree field of view, 15 degree pitch), its
lowest mask row touching the ground. Every ELM texel casts one hard shadow
of the card along its centre direction; the shadow is their sum with the
conventions' weights L_t W_t. The AO map is the card's own ambient
occlusion (the same sum under a uniform sky).

Edited AO maps steer the result near contact points: the received light is
scaled by the edited over the card's ambient visibility (A = AO^3).
"""

from __future__ import annotations

import hashlib

import numpy as np
from PIL import Image
from scipy.ndimage import map_coordinates

from ..camera import Camera
from ..hemisphere import texel_centres, texel_weights
from .base import check_batch

INTERNAL = 128  # the card is traced at this resolution, then upsampled
AO_GRID = 6  # texel rows of the uniform sky used for the card's AO
MIN_SHARE = 1e-4
TURN = 0.5  # share of the way the card turns towards each light  # texels carrying less of the ELM's weight are skipped


def _resize(image: np.ndarray, size: int) -> np.ndarray:
    if image.shape[0] == size:
        return image.astype(np.float32)
    return np.asarray(Image.fromarray(image.astype(np.float32), "F").resize((size, size), Image.Resampling.BILINEAR))


class _Card:
    """The card and camera for one mask at the internal resolution."""

    def __init__(self, mask: np.ndarray) -> None:
        m = mask.shape[0]
        self.mask = mask
        rows = np.flatnonzero((mask > 0.05).any(axis=1))
        if rows.size == 0:
            self.empty = True
            return
        self.empty = False
        top, base = float(rows[0]), float(rows[-1] + 1)
        solid = np.flatnonzero((mask > 0.5).any(axis=1))
        # The card reaches the ground: below its lowest solid row it continues that row,
        # so the antialiased bottom edge does not leave a lit seam at the contact line.
        self.lowest_centre = float(solid[-1] if solid.size else rows[-1]) + 0.5
        # Find the card height whose projection spans the mask's rows.
        height = 0.5
        for _ in range(12):
            cam = Camera(m, height / 2)
            span = cam.project(np.array([0.0, 0.0, 0.0]))[1] - cam.project(np.array([0.0, height, 0.0]))[1]
            height *= (base - top) / span
        cam = Camera(m, height / 2)
        cam.shift = base - cam.project(np.array([0.0, 0.0, 0.0]))[1]
        self.camera, self.height = cam, height
        ground, self.valid = cam.ground_points()
        self.ground = ground[self.valid]  # (P, 3)

    def occlusion(self, directions: np.ndarray) -> np.ndarray:
        """Hard-shadow occlusion (T, P) of the card turned towards each world direction (T, 3).

        For each light the card turns about its vertical axis part of the way
        (``TURN``) towards facing the light's horizontal direction, never
        more than 45 degrees from facing the camera: a card edge-on to the
        light would cast a line, while a fully turned one would lift half of
        its base off its contact shadow. Its point (x, h) casts onto the
        ground at x * axis - h * w_h / w_y.
        """
        g = self.ground
        w = directions.astype(np.float64)
        azimuth = np.arctan2(w[:, 0], -w[:, 2])  # from the horizontal forward (0, 0, -1)
        facing = np.where(azimuth > np.pi / 2, azimuth - np.pi, np.where(azimuth < -np.pi / 2, azimuth + np.pi, azimuth))
        turn = TURN * facing
        ax, az = np.cos(turn), np.sin(turn)  # the card's horizontal axis: right (1, 0, 0) turned
        wy = np.maximum(w[:, 1], 1e-6)
        dx, dz = -w[:, 0] / wy, -w[:, 2] / wy
        det = ax * dz - az * dx
        det = np.where(np.abs(det) > 1e-9, det, 1e-9)
        gx, gz = g[None, :, 0], g[None, :, 2]
        x = (gx * dz[:, None] - gz * dx[:, None]) / det[:, None]
        h = (ax[:, None] * gz - az[:, None] * gx) / det[:, None]
        hit = (h >= 0) & (h <= self.height * 1.001)
        points = np.stack([x, np.where(hit, h, 0.0), np.zeros_like(x)], axis=-1)
        image = self.camera.project(points)
        row = np.minimum(image[..., 1], self.lowest_centre)
        values = map_coordinates(
            self.mask, [row.ravel() - 0.5, image[..., 0].ravel() - 0.5], order=1, cval=0.0
        ).reshape(hit.shape)
        return np.where(hit, values, 0.0)

    def shadow(self, elm_weights: np.ndarray, directions: np.ndarray) -> np.ndarray:
        """Weighted sum of hard shadows, as an (m, m) frame."""
        m = self.mask.shape[0]
        out = np.zeros((m, m), np.float32)
        total = elm_weights.sum()
        if self.empty or total <= 0:
            return out
        share = elm_weights / total
        keep = share > MIN_SHARE
        occ = self.occlusion(directions[keep])
        out[self.valid] = share[keep] @ occ / share[keep].sum()
        return np.clip(out, 0.0, 1.0)


class GeometricCard:
    """Flat-card hard-shadow sum: the baseline and the fallback without a model."""

    name = "geometric"

    def __init__(self, resolution: int = 256) -> None:
        self.resolution = resolution
        cam = Camera(INTERNAL, 0.5)
        self._dirs16 = cam.to_world(texel_centres(16))  # (16, 32, 3)
        self._w16 = texel_weights(16)
        self._dirs_ao = cam.to_world(texel_centres(AO_GRID)).reshape(-1, 3)
        self._w_ao = texel_weights(AO_GRID).ravel()

        self._cache: tuple[bytes, _Card, np.ndarray] | None = None

    def _card(self, mask: np.ndarray) -> tuple[_Card, np.ndarray]:
        """The card for a mask and its AO at the internal resolution (last mask cached)."""
        key = hashlib.blake2b(np.ascontiguousarray(mask, np.float32).tobytes(), digest_size=16).digest()
        if self._cache is None or self._cache[0] != key:
            card = _Card(_resize(mask, INTERNAL))
            ao = (1.0 - card.shadow(self._w_ao, self._dirs_ao)) ** (1.0 / 3.0)
            self._cache = (key, card, ao)
        return self._cache[1], self._cache[2]

    def _blocks(self, weights: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """Merge 2 x 2 texels into one light at their weighted mean direction (128 at most)."""
        w = weights.reshape(8, 2, 16, 2).sum(axis=(1, 3)).ravel()
        d = (weights[..., None] * self._dirs16).reshape(8, 2, 16, 2, 3).sum(axis=(1, 3)).reshape(-1, 3)
        d /= np.maximum(np.linalg.norm(d, axis=-1, keepdims=True), 1e-12)
        return w, d

    def predict_ao(self, masks: np.ndarray) -> np.ndarray:
        check_batch(masks, None, self.resolution)
        return np.stack([_resize(self._card(m)[1], self.resolution) for m in masks]).clip(0, 1)

    def render(self, masks: np.ndarray, ao: np.ndarray, elms: np.ndarray) -> np.ndarray:
        check_batch(masks, elms, self.resolution, ao)
        out = []
        for mask, edited, elm in zip(masks, ao, elms):
            card, card_ao = self._card(mask)
            if elm.max() <= 0:
                out.append(np.zeros(mask.shape, np.float32))
                continue
            s = _resize(card.shadow(*self._blocks(np.maximum(elm, 0) * self._w16)), self.resolution)
            # Both visibilities at frame resolution, so an unedited AO map changes nothing.
            card_visibility = np.maximum(_resize(card_ao, self.resolution), 1e-3) ** 3
            edited_visibility = np.clip(edited, 0, 1) ** 3
            out.append(1.0 - np.clip((1.0 - s) * edited_visibility / card_visibility, 0.0, 1.0))
        return np.clip(np.stack(out), 0.0, 1.0).astype(np.float32)
