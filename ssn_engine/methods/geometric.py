"""The non-learned baseline: the cutout as a flat vertical card.

The mask is taken to be a card standing upright on the ground, facing the
camera of the conventions (45 degree field of view, 15 degree pitch), its
lowest mask row touching the ground. Every texel of the 16 x 32 ELM casts
one hard shadow of the card along its centre direction; the shadow is their
sum with the conventions' weights L_t W_t. The AO map is the card's own
ambient occlusion (the same sum under a uniform sky). The hard shadows are
traced once per mask (like the training data's bases), so moving a light
costs one weighted sum.

Edited AO maps steer the result near contact points: the received light is
scaled by the edited over the card's ambient visibility (A = AO^3).
"""

from __future__ import annotations

import collections
import hashlib

import numpy as np
from PIL import Image
from scipy.ndimage import map_coordinates

from ..camera import Camera
from ..hemisphere import texel_centres, texel_weights
from .base import check_batch

INTERNAL = 128  # the card is traced at this resolution, then upsampled
TURN = 0.5  # share of the way the card turns towards each light
CHUNK = 64  # directions traced at once (bounds memory)
CACHED_CARDS = 4


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
        self.ground = ground[self.valid].astype(np.float32)  # (P, 3)

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
        w = directions.astype(np.float32)
        azimuth = np.arctan2(w[:, 0], -w[:, 2])  # from the horizontal forward (0, 0, -1)
        facing = np.where(azimuth > np.pi / 2, azimuth - np.pi, azimuth)
        facing = np.where(facing < -np.pi / 2, facing + np.pi, facing)
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
        col, row = self.camera.project_xyz(x, np.where(hit, h, 0.0), 0.0)
        row = np.minimum(row, self.lowest_centre)
        values = map_coordinates(self.mask, [row.ravel() - 0.5, col.ravel() - 0.5], order=1, cval=0.0)
        values = values.reshape(hit.shape)
        return np.where(hit, values, 0.0)

    def trace(self, directions: np.ndarray) -> None:
        """Trace the hard shadow of every direction (T, 3) once: ``self.bases`` (T, P) float32."""
        self.bases = np.zeros((len(directions), len(self.ground) if not self.empty else 0), np.float32)
        if self.empty:
            return
        for i in range(0, len(directions), CHUNK):
            self.bases[i : i + CHUNK] = self.occlusion(directions[i : i + CHUNK])

    def shadow(self, weights: np.ndarray) -> np.ndarray:
        """The weighted mean (m, m) of the traced hard shadows, weights (T,) >= 0."""
        m = self.mask.shape[0]
        out = np.zeros((m, m), np.float32)
        total = float(weights.sum())
        if self.empty or total <= 0:
            return out
        out[self.valid] = (weights / total).astype(np.float32) @ self.bases
        return np.clip(out, 0.0, 1.0)


class GeometricCard:
    """Flat-card hard-shadow sum: the baseline and the fallback without a model."""

    name = "geometric"

    def __init__(self, resolution: int = 256) -> None:
        self.resolution = resolution
        self._dirs = Camera(INTERNAL, 0.5).to_world(texel_centres(16)).reshape(-1, 3)
        self._weights = texel_weights(16).ravel()
        self._cache: collections.OrderedDict[bytes, tuple[_Card, np.ndarray]] = collections.OrderedDict()

    def _card(self, mask: np.ndarray) -> tuple[_Card, np.ndarray]:
        """The traced card for a mask and its AO at the internal resolution (recent masks cached)."""
        key = hashlib.blake2b(np.ascontiguousarray(mask, np.float32).tobytes(), digest_size=16).digest()
        if key not in self._cache:
            card = _Card(_resize(mask, INTERNAL))
            card.trace(self._dirs)
            ao = (1.0 - card.shadow(self._weights)) ** (1.0 / 3.0)
            self._cache[key] = (card, ao)
            while len(self._cache) > CACHED_CARDS:
                self._cache.popitem(last=False)
        self._cache.move_to_end(key)
        return self._cache[key]

    def predict_ao(self, masks: np.ndarray) -> np.ndarray:
        check_batch(masks, None, self.resolution)
        return np.stack([_resize(self._card(m)[1], self.resolution) for m in masks]).clip(0, 1)

    def render(self, masks: np.ndarray, ao: np.ndarray, elms: np.ndarray) -> np.ndarray:
        check_batch(masks, elms, self.resolution, ao)
        out = []
        for mask, edited, elm in zip(masks, ao, elms, strict=True):
            card, card_ao = self._card(mask)
            if elm.max() <= 0:
                out.append(np.zeros(mask.shape, np.float32))
                continue
            s = _resize(card.shadow(np.maximum(elm, 0).ravel() * self._weights), self.resolution)
            # Both visibilities at frame resolution, so an unedited AO map changes nothing.
            card_visibility = np.maximum(_resize(card_ao, self.resolution), 1e-3) ** 3
            edited_visibility = np.clip(edited, 0, 1) ** 3
            out.append(1.0 - np.clip((1.0 - s) * edited_visibility / card_visibility, 0.0, 1.0))
        return np.clip(np.stack(out), 0.0, 1.0).astype(np.float32)
