"""The non-learned baseline: the cutout as a flat vertical card.

The mask is taken to be a card standing upright on the ground, facing the
camera of the conventions, its lowest mask row touching the ground. The
camera is the conventions' default (45 degree field of view, 15 degree
pitch) or, given the camera input (horizon row and focal length), the one
whose horizon lies on that row (:func:`ssn_engine.camera.camera_for_span`).
Every texel of the 16 x 32 ELM casts one hard shadow of the card along its
centre direction, and a texel holding at least ``AREA_SHARE`` of the light
the mean of the hard shadows along a 3 x 3 grid of directions over its area
(one direction per texel leaves a small light's shadow as separate streaks,
one per texel, 11 degrees apart; broad lights, whose texels each hold less,
blend their streaks by themselves); the shadow is their sum with the
conventions' weights L_t W_t. The AO map is the card's own ambient
occlusion (the same sum under a uniform sky). Each texel's shadow is traced
the first time a light needs it and kept (like the training data's bases),
so moving a light costs one weighted sum plus the texels it newly reaches.

Edited AO maps steer the result near contact points: the received light is
scaled by the edited over the card's ambient visibility (A = AO^3).
"""

from __future__ import annotations

import collections

import numpy as np

from ..camera import Camera, camera_for_span, fov_from_focal
from ..frames import frame_key, resample_frames
from ..hemisphere import stratified_directions, texel_centres, texel_weights
from .base import check_batch

INTERNAL = 128  # the card is traced at this resolution, then upsampled
TURN = 0.5  # share of the way the card turns towards each light
CHUNK = 64  # directions traced at once (bounds memory)
WIDE_CHUNK = 16  # directions traced at once on the wider grid, whose many points make larger chunks slower
CACHED_CARDS = 2  # a card traced for every texel holds 512 x P float32 (about 30 MB)
NEGLIGIBLE = 1e-4  # share of a light map's weight whose texels a card shadow may leave out
EXTENDED_TEXELS = 64  # at most this many texels traced beyond the frame per light map
AREA_SAMPLES = 9  # directions over a texel's area (3 x 3 strata) whose hard shadows make a bright texel's shadow
AREA_SHARE = 0.05  # share of a light map's weight from which a texel's shadow is traced over its area
WIDE_KEPT = 256  # texel shadows kept per card on the wider grid (about 100 kB each)


def _resize(image: np.ndarray, size: int) -> np.ndarray:
    """One (H, H) frame resampled to (size, size) (:func:`~ssn_engine.frames.resample_frames`)."""
    return resample_frames(image[None], size)[0]


class _Card:
    """The card and camera for one mask at the internal resolution."""

    def __init__(
        self,
        mask: np.ndarray,
        directions: np.ndarray,
        area_directions: np.ndarray,
        weights: np.ndarray,
        camera: tuple[float, float] | None = None,
    ) -> None:
        m = mask.shape[0]
        self.mask, self.directions, self.weights = mask, directions, weights
        self.area_directions = area_directions  # (T, S, 3): directions over each texel's area
        self._ao: np.ndarray | None = None
        self._grid: tuple | None = None  # (margin, cell), ground points, valid: the wider grid of ground_grid
        self._wide: dict[tuple[int, bool], np.ndarray] = {}  # (texel, over its area) -> its shadow on the wider grid
        self._area: dict[int, np.ndarray] = {}  # texel -> its shadow over its area on the frame's ground points
        rows = np.flatnonzero((mask > 0.05).any(axis=1))
        if rows.size == 0:
            self.empty = True
            self._ao = np.ones((m, m), np.float32)
            return
        self.empty = False
        top, base = float(rows[0]), float(rows[-1] + 1)
        solid = np.flatnonzero((mask > 0.5).any(axis=1))
        # The card reaches the ground: below its lowest solid row it continues that row,
        # so the antialiased bottom edge does not leave a lit seam at the contact line.
        self.lowest_centre = float(solid[-1] if solid.size else rows[-1]) + 0.5
        horizon, focal = camera if camera is not None else (None, None)
        self.camera, self.height = camera_for_span(m, top, base, horizon, focal)
        self.x_range = self._x_range(np.flatnonzero((mask > 0).any(axis=0)))
        ground, self.valid = self.camera.ground_points()
        self.ground = ground[self.valid].astype(np.float32)  # (P, 3)
        self._padded = np.pad(mask.astype(np.float32), 1)  # bilinear taps never leave it
        self.bases = np.zeros((len(directions), len(self.ground)), np.float32)
        self.traced = np.zeros(len(directions), bool)
        # Per texel, the ground points [span_lo, span_hi) between its first and last shadowed one: a shadow covers
        # a band of the ground, so a sum over texels reads only the band (an empty span: no shadow, not traced yet).
        self.span_lo = np.full(len(directions), len(self.ground), np.int64)
        self.span_hi = np.zeros(len(directions), np.int64)

    def _x_range(self, cols: np.ndarray) -> tuple[float, float]:
        """The card's horizontal coordinates x that can project onto the mask's columns ``cols`` (bilinear taps
        included) at any height on it: col = N/2 + f x / depth, with depth linear in the height."""
        cam, half = self.camera, 0.5 * self.mask.shape[0]
        depths = [(h - cam.centre[1]) * cam.view[1] - cam.centre[2] * cam.view[2] for h in (0.0, 1.001 * self.height)]
        xs = [(c - half) * d / cam.focal for c in (cols[0] - 1.0, cols[-1] + 2.0) for d in depths]
        return float(min(xs)), float(max(xs))

    def _sample(self, col: np.ndarray, row: np.ndarray) -> np.ndarray:
        """The mask bilinearly interpolated at continuous (col, row) points (pixel centres at k + 0.5); 0 outside."""
        m = self.mask.shape[0]
        x = np.clip(col - 0.5, -1.0, m) + 1.0  # padded coordinates
        y = np.clip(row - 0.5, -1.0, m) + 1.0
        x0 = np.minimum(np.floor(x), m).astype(np.intp)
        y0 = np.minimum(np.floor(y), m).astype(np.intp)
        fx, fy = (x - x0).astype(np.float32), (y - y0).astype(np.float32)
        flat, w = self._padded.ravel(), m + 2
        i = y0 * w + x0
        top = flat[i] * (1 - fx) + flat[i + 1] * fx
        bottom = flat[i + w] * (1 - fx) + flat[i + w + 1] * fx
        return top * (1 - fy) + bottom * fy

    def ground_grid(self, margin: float, cell: float) -> tuple[np.ndarray, np.ndarray]:
        """Ground points (P, 3) of a grid reaching ``margin`` frames beyond each side of the frame, with cells of
        ``cell`` internal pixels, and where its rays reach the ground: the same camera with a wider field."""
        if self._grid is None or self._grid[0] != (margin, cell):
            self._wide = {}
            n = int(round(self.mask.shape[0] * (1 + 2 * margin) / cell))
            cam = self.camera
            wide = Camera(
                n, cam.target_height, fov=fov_from_focal(n, cam.focal / cell), pitch=cam.pitch, shift=cam.shift / cell
            )
            ground, valid = wide.ground_points()
            self._grid = ((margin, cell), ground[valid].astype(np.float32), valid)
        return self._grid[1], self._grid[2]

    def texel_shadows(
        self, texels: np.ndarray | list[int], over_area: bool, ground: np.ndarray | None = None
    ) -> np.ndarray:
        """The shadows (k, P) of ``texels`` on the frame's ground points or on ``ground``: each the hard shadow along
        the texel's centre direction, or (``over_area``) the mean of those along its ``area_directions``."""
        dirs = self.area_directions[texels] if over_area else self.directions[texels][:, None]
        # texels traced at once: their (k S, P) stays in cache
        per_chunk = max(1, (CHUNK if ground is None else WIDE_CHUNK) // dirs.shape[1])
        points = len(self.ground if ground is None else ground)
        out = np.zeros((len(texels), points), np.float32)
        for i in range(0, len(texels), per_chunk):
            part = dirs[i : i + per_chunk]
            out[i : i + per_chunk] = (
                self.occlusion(part.reshape(-1, 3), ground).reshape(len(part), part.shape[1], -1).mean(axis=1)
            )
        return out

    def area_bases(self, texels: np.ndarray) -> np.ndarray:
        """The shadows (k, P) of ``texels`` over their areas on the frame's ground points, each traced once and kept."""
        todo = [int(t) for t in texels if int(t) not in self._area]
        for t, row in zip(todo, self.texel_shadows(todo, True), strict=True):
            self._area[t] = row
        return (
            np.stack([self._area[int(t)] for t in texels])
            if len(texels)
            else np.zeros((0, len(self.ground)), np.float32)
        )

    def wide_bases(self, texels: np.ndarray, ground: np.ndarray, area: np.ndarray) -> np.ndarray:
        """The shadows (k, P) of ``texels`` on the wider grid's ``ground``, each traced once and kept: along the
        texel's centre direction, or where ``area`` (k,) is set over its area."""
        keys = [(int(t), bool(a)) for t, a in zip(texels, area, strict=True)]
        for over_area in (False, True):
            todo = [t for t, a in keys if a == over_area and (t, a) not in self._wide]
            for t, row in zip(todo, self.texel_shadows(todo, over_area, ground), strict=True):
                self._wide[t, over_area] = row
        for k in keys:  # most recently used last
            self._wide[k] = self._wide.pop(k)
        while len(self._wide) > WIDE_KEPT:  # a light map needs at most EXTENDED_TEXELS of them
            del self._wide[next(iter(self._wide))]
        return np.stack([self._wide[k] for k in keys])

    def occlusion(self, directions: np.ndarray, ground: np.ndarray | None = None) -> np.ndarray:
        """Hard-shadow occlusion (T, P) of the card turned towards each world direction (T, 3), on the frame's
        ground points or on ``ground`` (P, 3).

        For each light the card turns about its vertical axis part of the way
        (``TURN``) towards facing the light's horizontal direction, never
        more than 45 degrees from facing the camera: a card edge-on to the
        light would cast a line, while a fully turned one would lift half of
        its base off its contact shadow. Its point (x, h) casts onto the
        ground at x * axis - h * w_h / w_y.
        """
        g = self.ground if ground is None else ground
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
        # Only rays through the card's bounding box can hit it: fewer points to project and sample.
        hit = (h >= 0) & (h <= self.height * 1.001) & (x >= self.x_range[0]) & (x <= self.x_range[1])
        out = np.zeros(hit.shape, np.float32)
        col, row = self.camera.project_xyz(x[hit], h[hit], np.zeros(1, np.float32))
        out[hit] = self._sample(col, np.minimum(row, self.lowest_centre))
        return out

    def trace(self, texels: np.ndarray | None = None) -> None:
        """Trace the hard shadows of ``texels`` (indices; None: all) not traced yet into ``self.bases`` (T, P)."""
        if self.empty:
            return
        todo = np.flatnonzero(~self.traced) if texels is None else texels[~self.traced[texels]]
        shadows = self.texel_shadows(todo, False)
        self.bases[todo] = shadows
        self.traced[todo] = True
        cast = shadows != 0
        some = cast.any(axis=1)
        self.span_lo[todo] = np.where(some, cast.argmax(axis=1), cast.shape[1])
        self.span_hi[todo] = np.where(some, cast.shape[1] - cast[:, ::-1].argmax(axis=1), 0)

    def shadow(self, weights: np.ndarray) -> np.ndarray:
        """The weighted mean (m, m) of the texels' shadows, weights (T,) >= 0: over their areas for the texels
        holding at least ``AREA_SHARE`` of the weight, along their centre directions for the others. Only the
        texels that hold all but ``NEGLIGIBLE`` of the weight count; those not traced yet are traced now (a light
        drag traces a few)."""
        m = self.mask.shape[0]
        out = np.zeros((m, m), np.float32)
        if self.empty or float(weights.sum()) <= 0:
            return out
        used = brightest(weights, 1.0 - NEGLIGIBLE)
        w = (weights / weights[used].sum()).astype(np.float32)
        over_area = w[used] >= AREA_SHARE
        bright = used[over_area]
        self.trace(used[~over_area])
        # einsum, not a BLAS product: BLAS threads left spinning after the call slow the network run that follows
        # by more than the product costs. Over runs of consecutive texels (a light covers a few ELM rows): only
        # the rows of the texels used are read, without copying them, and of those only the ground points where
        # one of the run's shadows falls (the rest adds zeros: the sum is the same to the bit, at half the reads).
        cut = np.flatnonzero(np.diff(used) != 1) + 1
        centre = w.copy()
        centre[bright] = 0.0
        total = np.zeros(self.bases.shape[1], np.float32)
        for run in np.split(used, cut):
            a, b = int(run[0]), int(run[-1]) + 1
            lo, hi = int(self.span_lo[a:b].min()), int(self.span_hi[a:b].max())
            if lo < hi:
                total[lo:hi] += np.einsum("t,tp->p", centre[a:b], self.bases[a:b, lo:hi])
        if bright.size:
            total += np.einsum("t,tp->p", w[bright], self.area_bases(bright))
        out[self.valid] = total
        return np.clip(out, 0.0, 1.0)

    @property
    def ao(self) -> np.ndarray:
        """The card's own AO map (m, m), A^(1/3): its shadow under a uniform sky (traces every texel once)."""
        if self._ao is None:
            self._ao = (1.0 - self.shadow(self.weights)) ** (1.0 / 3.0)
        return self._ao


def brightest(weights: np.ndarray, share: float, limit: int | None = None) -> np.ndarray:
    """Sorted indices of the fewest texels that hold ``share`` of the total weight (at most ``limit`` of them)."""
    order = np.argsort(-weights)
    count = int(np.searchsorted(np.cumsum(weights[order]), share * weights.sum())) + 1
    return np.sort(order[: count if limit is None else min(limit, count)])


def camera_at(cameras: np.ndarray | None, b: int) -> tuple[float, float] | None:
    """Frame ``b``'s camera input (horizon row, focal length), or None."""
    if cameras is None:
        return None
    h, f = cameras[b]
    return float(h), float(f)


class GeometricCard:
    """Flat-card hard-shadow sum: the baseline, the fallback without a model, and the network's proxy geometry."""

    name = "geometric"

    def __init__(self, resolution: int = 256, internal: int = INTERNAL) -> None:
        self.resolution, self.internal = resolution, internal
        to_world = Camera(internal, 0.5).to_world
        self._dirs = to_world(texel_centres(16)).reshape(-1, 3)
        self._area_dirs = to_world(stratified_directions(16, AREA_SAMPLES)).reshape(-1, AREA_SAMPLES, 3)
        self._weights = texel_weights(16).ravel()
        self._cache: collections.OrderedDict[bytes, _Card] = collections.OrderedDict()

    def card(self, mask: np.ndarray, camera: tuple[float, float] | None = None) -> _Card:
        """The card for a frame mask (camera input in frame pixels, or None: the default camera) at the internal
        resolution; recent cards are cached. Its hard shadows (``card.bases`` (T, P), T = 512 texel directions
        on the P ground pixels ``card.valid`` of the internal grid) are traced when first needed."""
        key = frame_key(mask, repr(camera).encode())
        if key not in self._cache:
            self._cache[key] = self._build(mask, camera)
            while len(self._cache) > CACHED_CARDS:
                self._cache.popitem(last=False)
        self._cache.move_to_end(key)
        return self._cache[key]

    def _build(self, mask: np.ndarray, camera: tuple[float, float] | None) -> _Card:
        """The card of a frame mask at the internal resolution (camera input in frame pixels, or None)."""
        scale = self.internal / mask.shape[0]
        internal_camera = None if camera is None else (camera[0] * scale, camera[1] * scale)
        return _Card(_resize(mask, self.internal), self._dirs, self._area_dirs, self._weights, internal_camera)

    def card_shadows(self, masks: np.ndarray, elms: np.ndarray, cameras: np.ndarray | None = None) -> np.ndarray:
        """The card's shadows (n, internal, internal) for frame masks (n, N, N) and ELMs (n, 16, 32)."""
        out = np.zeros((len(masks), self.internal, self.internal), np.float32)
        for b, (mask, elm) in enumerate(zip(masks, elms, strict=True)):
            if elm.max() > 0:
                out[b] = self.card(mask, camera_at(cameras, b)).shadow(np.maximum(elm, 0).ravel() * self._weights)
        return out

    def extended_shadow(
        self,
        mask: np.ndarray,
        elm: np.ndarray,
        camera: tuple[float, float] | None = None,
        margin: float = 1.0,
        cell: float = 4.0,
    ) -> np.ndarray:
        """The card's shadow on a grid reaching ``margin`` frames beyond every side of the frame, in cells of
        ``cell`` frame pixels: (M, M) covering frame coordinates [-margin N, (1 + margin) N) on both axes.

        Only the brightest texels, those that hold 99.5 % of the light (at most ``EXTENDED_TEXELS``), are
        traced, when the light changes: long shadows come from small lights, which cover few texels."""
        card = self.card(mask, camera)
        ground, valid = (
            card.ground_grid(margin, cell * self.internal / mask.shape[0])
            if not card.empty
            else (None, np.zeros((1, 1), bool))
        )
        out = np.zeros(valid.shape, np.float32)
        w = np.maximum(elm, 0).ravel() * self._weights
        if ground is None or w.sum() <= 0:  # ground is None: the card is empty
            return out
        keep = brightest(w, 0.995, EXTENDED_TEXELS)
        share = w[keep] / w[keep].sum()
        out[valid] = np.einsum("t,tp->p", share.astype(np.float32), card.wide_bases(keep, ground, share >= AREA_SHARE))
        return out

    def predict_ao(self, masks: np.ndarray, cameras: np.ndarray | None = None) -> np.ndarray:
        check_batch(masks, None, self.resolution, cameras=cameras)
        return np.stack(
            [_resize(self.card(m, camera_at(cameras, b)).ao, self.resolution) for b, m in enumerate(masks)]
        ).clip(0, 1)

    def render(
        self, masks: np.ndarray, ao: np.ndarray, elms: np.ndarray, cameras: np.ndarray | None = None
    ) -> np.ndarray:
        check_batch(masks, elms, self.resolution, ao, cameras)
        shadows = self.card_shadows(masks, elms, cameras)
        out = []
        for b, (mask, edited) in enumerate(zip(masks, ao, strict=True)):
            card_ao = self.card(mask, camera_at(cameras, b)).ao
            s = _resize(shadows[b], self.resolution)
            # Both visibilities at frame resolution, so an unedited AO map changes nothing.
            card_visibility = np.maximum(_resize(card_ao, self.resolution), 1e-3) ** 3
            edited_visibility = np.clip(edited, 0, 1) ** 3
            out.append(1.0 - np.clip((1.0 - s) * edited_visibility / card_visibility, 0.0, 1.0))
        out = np.stack(out)
        out[np.asarray(elms).max(axis=(1, 2)) <= 0] = 0.0  # no light, no shadow (conventions)
        return np.clip(out, 0.0, 1.0).astype(np.float32)
