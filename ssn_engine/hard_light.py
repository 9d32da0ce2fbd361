"""Shadows of small lights traced at the output's resolution: the cutout as a card, contact-hardened.

The network sees a 256-pixel frame and a 16 x 32 light map, so a sun's shadow
comes out as a smudge once enlarged onto a canvas. A light of small apparent
size (a disk light's ``angle``, or a narrow Gaussian's equivalent) is traced
here instead, on the output's own pixels (the canvas, a preview's scaled
canvas, or a frame).

Geometry: the cutout stands on its *contact line* (:func:`contact_line`), the
lower convex hull of its lowest solid pixels: a part standing farther back
(higher in the picture, a shoe's heel, the farther of two toys) stands on
the ground there, and a gap between legs spans from foot to foot; it rises
no faster than a footprint can show the camera (:func:`footprint_rise`), so
a ball seen along the ground stands on its lowest point. Along it
the cutout is cut into bands (:func:`contact_bands`), each the geometric
method's card (:mod:`ssn_engine.methods.geometric`): a flat card standing
upright on its band's contact row, facing the camera of the conventions
(given, or the one the model read), cross-faded into its neighbours. For one
light direction, each ground point seen through an output pixel is moved
along the light to the card, and the card point projected back into the
cutout: the three steps (pixel to ground plane, ground plane to card plane
along a fixed direction, card plane to image) are projective maps, so a
card's hard shadow is one homography of the cutout's alpha, resampled by
Pillow.

Depth: a card alone casts a line under a light from its side, and nothing of
a body that reaches away from the camera. Each pixel shows a surface on its
card, or, with a model's pixel heights (:func:`foot_rows`: how far below
each pixel the image of the ground under its surface lies), that far behind
the card along its camera ray (or in front of it, by at most its own depth:
a ball's front, a lowered head); from there it reaches deeper by a depth
(:func:`depth_map`): the chord of a round cross-section as wide as the part
it lies in (a body as deep as it is wide, a leg thin; never below the
ground). The card is swept through that span before the homography: each
pixel repeated along the shift its shadow makes as it moves deeper, from
where its own shift puts its surface to where its depth ends (each span as
one or two segments a power of two long, each length drawn once by doubling
over all its copies, in cells each along its own shift; a card larger than
``SWEEP_SIZE`` is swept on a reduced copy, the card itself kept crisp). A
light from nearly the card's side still turns it a little
(``MIN_INCIDENCE``), so that no card is seen edge-on.

Size: a disk light of apparent diameter ``angle`` seen from a ground point a
distance D below a card point along the light blurs the card over a circle of
radius D tan(angle / 2) around it, and D = h / w_y grows with the card
point's height h above the ground. So the cutout is blurred row by row, by a
radius that is zero at the contact line and grows with the height, before the
homography: the shadow is crisp at the contact and softens with distance
(contact hardening); the sweep through the depth comes after the blur. The
varying blur interpolates between Gaussian-blurred copies of the cutout
(``LEVELS_PER_OCTAVE`` per doubling of the radius, kept per source
resolution), a Gaussian of sigma r / 2 standing in for the disk of radius r.
The disk's footprint on the card is taken to be round (it is an ellipse where
the light strikes the card obliquely).
"""

from __future__ import annotations

import math
from collections.abc import Callable
from dataclasses import dataclass, field
from functools import partial

import numpy as np
from PIL import Image, ImageFilter
from scipy import ndimage

from .camera import FORWARD, RIGHT, UP, Camera, camera_for_span
from .frames import nearest_fill
from .framing import Framing, placed_sum
from .hemisphere import direction
from .stripes import for_each_stripe


DEPTH_SIZE = 128  # pixels: the object's depth is worked out on a copy reduced to about this size
RIDGE_RISE = 0.7  # a pixel whose distance to the outline rises towards a neighbour by this share of the step
# or more lies inside that neighbour's inscribed disk, nearly: it centres no disk of its own (an interior pixel's
# rise is at least cos 22.5 = 0.92 towards one of its 8 neighbours; the ridge's, across it, about 0)
FADE_STEP = 3.0  # pixels of shift: a pixel's shadow fades out in steps of falling value at most this long
MAX_FADE_STEPS = 8  # steps at most (a long fade's are longer)
# pixels of the cutout: a shorter fade ends its pixel's depth crisply; its few steps, each pixel's ending where its
# own depth does, would show as hairs and a flat grey band, magnified by the ground's projection under a low sun
MIN_FADE = 8.0
SWEEP_BLUR_SHARE = 10.0  # percent of a card's rows blurred less than the pixel of the copy its depth is swept on
SWEEP_SIZE = 400  # pixels: a larger card is swept through its depth on a copy reduced to about this size
MIN_INCIDENCE = 10.0  # degrees: the card turns just enough that a light's horizontal direction meets it at least so

__all__ = [
    "TRACED_FULL_ANGLE",
    "TRACED_MAX_ANGLE",
    "CardTracer",
    "ContactTracer",
    "contact_bands",
    "contact_line",
    "depth_map",
    "footprint_rise",
    "ground_ahead",
    "ground_rows",
    "light_direction",
    "local_radius",
    "read_thickness",
    "rigid_lifts",
    "traced_share",
]

TRACED_FULL_ANGLE = 12.0  # degrees: a light this small or smaller (a disk's angle, a Gaussian's equivalent) is traced
TRACED_MAX_ANGLE = 20.0  # degrees: from this size a light is left to the network; between, cross-faded

SOLID = 0.5  # the lowest row with alpha above this is the card's foot: the rows below it repeat it
ROWS_ALPHA = 0.05  # rows with alpha above this span the card (as the geometric card's)
LEVELS_PER_OCTAVE = 2  # blurred copies of the cutout per doubling of the blur
MIN_SIGMA = 0.35  # pixels: a blur below this is left sharp
WIDE_BLUR = 4.0  # pixels: a wider blur is made on a copy reduced this many times fewer than its sigma
SUPERSAMPLE = 4  # at most this many samples across each output pixel coarser than the cutout's canvas
BAND = 64  # output rows resampled at once (each band only over the columns the shadow can reach)
MIN_W = 1e-6  # a card point whose output w is below this share of its box's largest lies at the horizon
STEP_TOLERANCE = 1.0  # pixels: a card is swept in cells, each along one shift with depth, so that no pixel's
# deepest copy lies farther than this from where its own shift puts it
MAX_STEP_CELLS = (2, 2)  # cells down and across a card at most
Cell = tuple[int, int, int, int, np.ndarray]  # rows r0:r1 and columns c0:c1 of a card swept along one step
SLABS = 8  # bands of a card's rows whose boxes' outlines on the output bound where its warp is resampled
RUN_GAP = 32  # output columns: two runs of a band to resample closer than this are resampled as one
RUN_MARGIN = 2  # output columns resampled beyond a run's ends
HORIZON_GAP = 0.02  # share of the frame below the horizon that a foot's row is kept to (the ground recedes to
# infinity at the horizon: a foot read there is read a little nearer)
MAX_SURFACE_DEPTH = 2.0  # a pixel's surface lies behind its card by at most this many times the cutout's size
PAD = 0.25  # share of the cutout's size added above and beside it, where its blurred copies spread
PAD_STEP = 64  # pixels: a lifted card's pad grows with the lift in steps of this
UNCLIPPED_MARGIN = 0.5  # share of the canvas a layer that may leave the canvas reaches beyond each side


def light_direction(u: float, v: float) -> np.ndarray:
    """The world direction (3,) towards map point (u, v) (conventions: elevation 90 (1 - v), azimuth
    360 u - 180 degrees from the camera's horizontal forward, positive to its right)."""
    right, up, forward = direction(np.radians(90.0 * (1.0 - v)), np.radians(360.0 * u - 180.0))
    return right * RIGHT + up * UP + forward * FORWARD


def traced_share(angle: float) -> float:
    """The share of a light of ``angle`` degrees that is traced: all of it up to ``TRACED_FULL_ANGLE``, none
    from ``TRACED_MAX_ANGLE``, linearly between (the rest goes to the network), so that resizing a light never
    makes its shadow jump."""
    return min(1.0, max(0.0, (TRACED_MAX_ANGLE - angle) / (TRACED_MAX_ANGLE - TRACED_FULL_ANGLE)))


@dataclass(frozen=True)
class _Level:
    """A blurred copy of a source in 8 bits, kept only over its non-zero part: ``values`` at (x, y)."""

    values: np.ndarray
    x: int
    y: int

    @classmethod
    def of(cls, alpha: np.ndarray, y: int = 0) -> _Level:
        """``alpha`` (float in [0, 1]; uint8 as it is) in 8 bits, cropped to where it is non-zero; its row 0 is
        the source's row ``y``."""
        q = alpha if alpha.dtype == np.uint8 else np.round(np.asarray(alpha, np.float32) * 255).astype(np.uint8)
        rows, cols = np.flatnonzero(q.any(axis=1)), np.flatnonzero(q.any(axis=0))
        if rows.size == 0:
            return cls(np.zeros((0, 0), np.uint8), 0, 0)
        return cls(q[rows[0] : rows[-1] + 1, cols[0] : cols[-1] + 1].copy(), int(cols[0]), y + int(rows[0]))

    def paste(self, out: np.ndarray, r0: int, r1: int, shift: int = 0) -> None:
        """Write this level's rows [r0, r1) (of the source, less ``shift``: rows of ``out``) into ``out`` (zeros
        there beforehand)."""
        y = self.y + shift
        a, b = max(r0, y), min(r1, y + self.values.shape[0])
        if b > a:
            out[a:b, self.x : self.x + self.values.shape[1]] = self.values[a - y : b - y]


@dataclass(frozen=True)
class _Source:
    """The cutout's alpha at one resolution: (h, w) float32 with its foot rows filled, how its pixels map to
    frame coordinates: frame = pixel * scale + (offset_x, offset_y), and ``lit_rows``: one past its last row
    holding any of the cutout (below it lie the ground's rows down to the foot)."""

    alpha: np.ndarray
    scale: float
    offset_x: float
    offset_y: float
    lit_rows: int


@dataclass(frozen=True)
class _Padded:
    """A card's alpha and its surfaces' depths (pixels behind the card: where each pixel's surface lies, ``near``,
    and where its depth ends, ``far``) with its pad above and beside them, down to its foot and beyond it: the
    ground's rows, zeros (depths: the last row's), to the foot of the highest lift with the same pad. Read-only: a
    card whose foot lies lower (a lift dragged) takes them over to its own foot. ``given_thickness``: the
    artist's thickness they were made with (None: read); ``deepest`` and ``frontmost``: ``far``'s largest and
    ``-near``'s (pixels); ``cols``: the columns of ``alpha`` (without the pad) that hold any of it."""

    pad: int
    given_thickness: float | None
    alpha: np.ndarray
    near: np.ndarray
    far: np.ndarray
    deepest: float
    frontmost: float
    cols: tuple[int, int]

    @classmethod
    def of(
        cls,
        alpha: np.ndarray,
        near: np.ndarray,
        thick: np.ndarray,
        pad: int,
        rows: int,
        given_thickness: float | None,
    ) -> _Padded:
        """The arrays of a card of ``alpha`` (its rows down to its lowest lit one), ``near`` and ``thick`` (how deep
        each pixel reaches behind its surface) over the same rows, padded by ``pad`` to ``rows`` rows in all."""
        lowest, width = alpha.shape
        alpha = alpha.copy()
        solid = np.flatnonzero((alpha > SOLID).any(axis=1))
        if solid.size:  # the card reaches the ground: below its lowest solid row it continues that row
            alpha[solid[-1] + 1 :] = alpha[solid[-1]]
        cols = np.flatnonzero((alpha > 0).any(axis=0))
        # a surface in front of its card (a ball's, a lowered head's) lies no farther in front than its own depth:
        # every part reaches back to the card's plane (the surface model's pixel heights are noisy)
        near = np.maximum(near, -thick)
        far = near + thick
        out = np.zeros((rows, width + 2 * pad), np.float32)
        out[pad : pad + lowest, pad : pad + width] = alpha
        # the surface's depth reaches into the pad as it does around the outline within the crop (the blurred
        # copies spread there): a part read behind its card takes its blurred edge with it, leaving no trace of
        # it on the card; the pad sweeps no depth of its own (a part's edge is thin: the round cross-section)
        spread = np.empty_like(out)  # each pad pixel as its nearest border pixel (np.pad's "edge", in slices)
        spread[pad : pad + lowest, :pad] = near[:, :1]
        spread[pad : pad + lowest, pad : pad + width] = near
        spread[pad : pad + lowest, pad + width :] = near[:, -1:]
        spread[:pad] = spread[pad]
        spread[pad + lowest :] = spread[pad + lowest - 1]
        ends = spread.copy()
        ends[pad : pad + lowest, pad : pad + width] = far
        for values in (out, spread, ends):
            values.flags.writeable = False
        return cls(
            pad,
            given_thickness,
            out,
            spread,
            ends,
            max(float(far.max()), 0.0),
            max(float(-near.min()), 0.0),
            (int(cols[0]), int(cols[-1]) + 1),
        )


@dataclass(frozen=True)
class Kept:
    """What a card keeps for a card of the same cutout whose foot or depth differ (the artist's lift or thickness
    changed): per scale and level of its blurred copies, the rows blurred and the copy; its padded arrays (and
    their pad, which the copies share)."""

    levels: dict[float, dict[int, tuple[int, int, _Level]]]
    arrays: _Padded


SurfaceDepths = tuple[np.ndarray, np.ndarray | None]  # pixels behind the card: each surface's, its far end's read depth
BandKey = tuple[tuple[tuple[int, ...], ...], int]  # a card's bands ((c0, c1) or (c0, c1, foot)), which of them


class CardTracer:
    """Traces disk lights' shadows of one cutout's card at any output resolution.

    Parameters
    ----------
    alpha : np.ndarray
        The cutout's alpha (h, w) in [0, 1] (float) over its bounding box, at the finest resolution it will be
        traced at (a canvas crop, or a frame).
    framing : Framing
        The frame the session works in; ``framing.bbox`` gives where ``alpha`` lies on its canvas.
    camera : tuple of float or None
        The frame's camera input (horizon row, focal length in frame pixels), or None: the conventions' default.
    origin : tuple of int or None
        Where ``alpha``'s top-left pixel lies on the canvas (default: ``framing.bbox``'s corner).
    foot : int or None
        The row of ``alpha`` (one past it) on which the card stands, at or below its lowest row (default: that).
    thickness : np.ndarray or None
        (h, w) how deep (pixels) each pixel reaches behind its surface (:func:`depth_map`); None: to its far
        surface where ``far_feet`` are given, else nothing (a flat card).
    feet : np.ndarray or None
        (h, w) the row of ``alpha`` (continuous) of each pixel's foot: the image of the ground point straight
        below the surface the pixel shows (:func:`foot_rows`). Where it lies above the card's foot, the pixel's
        surface lies behind the card by the ground's distance between the two (:meth:`_surface_depth`); None:
        every surface on the card.
    far_feet : np.ndarray or None
        (h, w) as ``feet``, of each pixel's far surface (where the object's depth there ends, read by the surface
        model): with ``feet``, how deep each pixel reaches (:attr:`deepest_read`: the deepest, in pixels), which
        it does where ``thickness`` is None.
    lift : int
        How many of the rows down to ``foot`` are the artist's lift (the cutout floats): the pad above and beside
        the cutout grows with it in steps.
    at_rest : tuple or None
        The :attr:`surface_depths` of the card of the same ``alpha`` standing on the ground (lift 0), which a
        lifted card takes in place of its own reading of ``feet`` and ``far_feet``: the object's shape does not
        change as it floats (read at the lifted card's foot, nearer the camera, the same rows would make it
        shallower).
    given_thickness : float or None
        The artist's thickness that ``thickness`` was scaled to (None: the depth is read): ``kept``'s padded
        arrays are taken over only if made with the same.
    kept : Kept or None
        The :attr:`kept` of a card of the same ``alpha`` and origin whose foot or depth differ (the artist's lift
        or thickness changed): its blurred copies taken over where its pad is this one's, its padded arrays where
        its ``given_thickness`` is this one's too and they reach this card's foot.
    relief : float
        The share of their read distance behind or in front of the card that the surfaces keep: below 1 where
        the artist gives the object less depth than its outline reads, 0 for a flat sign, one plane (surfaces
        read at several depths with no depth to sweep drew a thin shadow's far part as dotted lines).
        :attr:`surface_depths` and :attr:`deepest_read` are the reading's.
    """

    def __init__(
        self,
        alpha: np.ndarray,
        framing: Framing,
        camera: tuple[float, float] | None,
        origin: tuple[int, int] | None = None,
        foot: int | None = None,
        thickness: np.ndarray | None = None,
        feet: np.ndarray | None = None,
        far_feet: np.ndarray | None = None,
        lift: int = 0,
        at_rest: SurfaceDepths | None = None,
        given_thickness: float | None = None,
        kept: Kept | None = None,
        relief: float = 1.0,
    ) -> None:
        alpha = np.clip(np.asarray(alpha, np.float32), 0.0, 1.0)
        x0, y0 = origin if origin is not None else framing.bbox[:2]
        s = framing.scale
        rows = np.flatnonzero((alpha > ROWS_ALPHA).any(axis=1))
        self.empty = rows.size == 0
        if self.empty:
            return
        foot = int(rows[-1]) + 1 if foot is None else max(int(foot), int(rows[-1]) + 1)
        top, base = rows[0] * s + framing.offset_y + y0 * s, foot * s + framing.offset_y + y0 * s
        horizon, focal = camera if camera is not None else (None, None)
        self.camera, self.height = camera_for_span(framing.n, top, base, horizon, focal)
        self._world_per_pixel = s * self._mid_depth() / float(self.camera.focal)  # at the card, per alpha pixel
        # a floating object's lowest point: the world height of its card's foot row before the lift
        self._floor = float(self._frame_row_geometry(np.array([base - lift * s]))[0][0]) if lift > 0 else 0.0
        lowest, width = int(rows[-1]) + 1, alpha.shape[1]
        if at_rest is not None:
            near, read = at_rest
        else:
            near = (
                np.zeros((lowest, width), np.float32)
                if feet is None
                else self._surface_depth(feet, framing, y0, base)[:lowest]
            )
            read = None
            if feet is not None and far_feet is not None:
                read = np.maximum(self._surface_depth(far_feet, framing, y0, base)[:lowest] - near, 0.0)
        self.surface_depths: SurfaceDepths = (near, read)
        self.deepest_read = 0.0 if read is None else float(read.max())
        # room for the blur above and beside the cutout (not below: ground); a lifted card's grows with the lift in
        # steps, so that a card whose foot moves a little (a lift dragged) keeps its pad and what it made there
        steps = math.ceil(PAD * lift / PAD_STEP)
        pad = math.ceil(PAD * max(foot - lift, width)) + PAD_STEP * steps
        same_pad = kept is not None and kept.arrays.pad == pad
        if (
            kept is not None  # (implied by same_pad; said again for the type checker)
            and same_pad
            and kept.arrays.given_thickness == given_thickness
            and len(kept.arrays.alpha) >= pad + foot
        ):
            arrays = kept.arrays
        else:
            if thickness is not None:
                thick = np.asarray(thickness[:lowest], np.float32)
            else:
                thick = np.zeros((lowest, width), np.float32) if read is None else read
            highest = int(PAD_STEP * steps / PAD)  # the highest lift with this pad
            relieved = near if relief == 1.0 else near * np.float32(relief)
            arrays = _Padded.of(alpha[:lowest], relieved, thick, pad, pad + foot + highest - lift, given_thickness)
        self.depth = arrays.deepest * self._world_per_pixel  # world units it reaches behind the card
        self.front = arrays.frontmost * self._world_per_pixel  # and in front of it
        c0, c1 = arrays.cols
        self._x_cols = (c0 * s + framing.offset_x + x0 * s, c1 * s + framing.offset_x + x0 * s)
        self._near = {1: arrays.near[: pad + foot]}  # per reduction: depth behind the card of the surface each pixel
        self._far = {1: arrays.far[: pad + foot]}  # shows, its pixels; and of its far end
        self._full = _Source(
            arrays.alpha[: pad + foot],
            s,
            framing.offset_x + (x0 - pad) * s,
            framing.offset_y + (y0 - pad) * s,
            pad + lowest,
        )
        self._sources: dict[int, _Source] = {}
        self._swept_depths: dict[tuple[int, int], tuple[np.ndarray, np.ndarray]] = {}  # per reduction and sweep's
        self._on_card: dict[int, np.ndarray | None] = {}  # per reduction: the pixels whose surface is on the card
        # per scale, level: rows, blurred; those of the same alpha with the same pad (a card whose foot moved) hold
        levels = kept.levels if kept is not None and same_pad else {}
        self.kept = Kept(levels, arrays)  # for a card of the same alpha and another foot or depth
        self._levels = levels

    # -- the cutout at the output's resolution ------------------------------------------------------------------
    def _source(self, out_scale: float) -> _Source:
        """The cutout reduced by a whole factor to about the output's resolution (``out_scale`` frame pixels per
        output pixel), never below it and never finer than the alpha given: the homography then magnifies or
        shrinks it by little (Pillow's resampling does not antialias)."""
        full = self._full
        k = int(out_scale / full.scale + 1e-6)
        if k <= 1:
            return full
        if k not in self._sources:
            h, w = full.alpha.shape
            padded = np.pad(full.alpha, ((0, -h % k), (0, -w % k)))  # zeros below the foot: ground, and right
            small = np.asarray(Image.fromarray(padded, "F").reduce(k))
            self._sources[k] = _Source(small, full.scale * k, full.offset_x, full.offset_y, -(-full.lit_rows // k))
            far, near = (np.pad(d[1], ((0, -h % k), (0, -w % k))) for d in (self._far, self._near))
            self._far[k] = far.reshape(h // k + (h % k > 0), k, -1, k).max(axis=(1, 3)) / k
            self._near[k] = near.reshape(h // k + (h % k > 0), k, -1, k).min(axis=(1, 3)) / k
        return self._sources[k]

    def _level(self, source: _Source, k: int, r0: int, r1: int) -> _Level:
        """The source blurred by a Gaussian of sigma ``MIN_SIGMA * 2^((k - 1) / LEVELS_PER_OCTAVE)`` pixels
        (k = 0: unblurred), over at least its rows [r0, r1): blurred only over the rows a light needs of it (each
        level serves a band of rows); asked for more (another light's, another lift's), it is blurred over the rows
        it lacks, at least as many as it has (a drag asks a few more each time: they are blurred seldom)."""
        levels = self._levels.setdefault(source.scale, {})
        kept = levels.get(k)
        sigma = MIN_SIGMA * 2.0 ** ((k - 1) / LEVELS_PER_OCTAVE)
        margin = math.ceil(4 * sigma) + 2  # rows beyond [lo, hi) that reach into it
        # below the cutout's rows and their blur lies nothing, however far down the foot (a lift's ground rows)
        last = min(source.alpha.shape[0], source.lit_rows + (margin if k > 0 else 0))
        r1 = min(r1, last)
        if r1 <= r0 or (kept is not None and kept[0] <= r0 and r1 <= kept[1]):
            return kept[2] if kept is not None else _Level.of(np.zeros((0, 0), np.float32))
        if k == 0:
            lo, hi, level = 0, source.alpha.shape[0], _Level.of(source.alpha)
        elif kept is None:
            lo, hi, level = r0, r1, self._blurred_rows(source, sigma, margin, r0, r1)
        else:
            k0, k1, old = kept
            grow = k1 - k0
            lo = min(r0, max(0, k0 - grow)) if r0 < k0 else k0
            hi = max(r1, min(last, k1 + grow)) if r1 > k1 else k1
            rows = np.zeros((hi - lo, source.alpha.shape[1]), np.uint8)
            for a, b in ((lo, k0), (k1, hi)):
                if b > a:
                    self._blurred_rows(source, sigma, margin, a, b).paste(rows, a - lo, b - lo, -lo)
            old.paste(rows, k0 - lo, k1 - lo, -lo)
            level = _Level.of(rows, lo)
        levels[k] = (lo, hi, level)
        return level

    @staticmethod
    def _blurred_rows(source: _Source, sigma: float, margin: int, lo: int, hi: int) -> _Level:
        """The source's rows [lo, hi) blurred by a Gaussian of ``sigma`` (with the ``margin`` rows either side that
        reach into them)."""
        a, b = max(0, lo - margin), min(source.alpha.shape[0], hi + margin)
        return _Level.of(_blur(source.alpha[a:b], sigma)[lo - a : hi - a], lo)

    def _blurred(self, source: _Source, sigma_rows: np.ndarray) -> np.ndarray:
        """The source (uint8) blurred row by row: row i by a Gaussian of about sigma ``sigma_rows[i]`` pixels (the
        nearest level's, ``LEVELS_PER_OCTAVE`` a doubling; under ``MIN_SIGMA``: sharp)."""
        level = np.log2(np.maximum(sigma_rows, 1e-9) / MIN_SIGMA) * LEVELS_PER_OCTAVE + 1.0
        level = np.where(level < 0.5, 0, np.round(level)).astype(int)
        out = np.zeros(source.alpha.shape, np.uint8)
        starts = np.flatnonzero(np.diff(level, prepend=-1))  # sigma grows with the height: bands of rows share a level
        for a, b in zip(starts, [*starts[1:], len(level)], strict=True):
            self._level(source, int(level[a]), int(a), int(b)).paste(out, int(a), int(b))
        return out

    # -- geometry ---------------------------------------------------------------------------------------------
    @staticmethod
    def _card_axis(w: np.ndarray) -> tuple[float, float]:
        """The card's horizontal axis (x, z): facing the camera, so that its foot is the cutout's lowest row,
        unless the light comes from nearly its side (it would cast a line): then turned about its vertical
        centre line just enough that the light meets it at ``MIN_INCIDENCE`` degrees."""
        azimuth = math.atan2(w[0], -w[2])
        facing = (
            azimuth - math.pi if azimuth > math.pi / 2 else azimuth + math.pi if azimuth < -math.pi / 2 else azimuth
        )
        limit = math.radians(90.0 - MIN_INCIDENCE)
        turn = math.copysign(max(0.0, abs(facing) - limit), facing)
        return math.cos(turn), math.sin(turn)

    def _homography(self, w: np.ndarray, framing: Framing, source: _Source, origin: tuple[int, int]) -> np.ndarray:
        """The 3 x 3 map from continuous output coordinates (relative to ``origin`` on ``framing``'s canvas) to
        continuous source coordinates: output pixel -> frame -> camera ray -> ground -> card along ``w`` ->
        frame -> source pixel."""
        cam = self.camera
        s, ox, oy = (
            framing.scale,
            framing.offset_x + origin[0] * framing.scale,
            framing.offset_y + origin[1] * framing.scale,
        )
        to_frame = np.array([[s, 0, ox], [0, s, oy], [0, 0, 1.0]])
        c = cam.centre
        ground = np.array([[-c[1], c[0], 0.0], [0.0, c[2], -c[1]], [0.0, 1.0, 0.0]])  # ray -> (gx, gz, 1)
        ax, az = self._card_axis(w)
        dx, dz = -w[0] / w[1], -w[2] / w[1]
        det = ax * dz - az * dx
        det = det if abs(det) > 1e-9 else 1e-9
        card = np.array([[dz, -dx, 0.0], [-az, ax, 0.0], [0.0, 0.0, det]])  # (gx, gz, 1) -> (x, h, 1)
        project = cam.projection()[:, [0, 1, 3]]  # the card's points (x, h, 0) -> frame
        to_source = np.array(
            [
                [1 / source.scale, 0, -source.offset_x / source.scale],
                [0, 1 / source.scale, -source.offset_y / source.scale],
                [0, 0, 1.0],
            ]
        )
        return to_source @ project @ card @ ground @ cam.ray_matrix() @ to_frame

    def _ground_to_output(self, points: np.ndarray, framing: Framing) -> np.ndarray:
        """Ground points (k, 3) to continuous output coordinates (k, 2); points behind the camera give nan."""
        col, row = self.camera.project_xyz(points[:, 0], points[:, 1], points[:, 2])
        depth = (points - self.camera.centre) @ self.camera.view
        out = np.stack([(col - framing.offset_x) / framing.scale, (row - framing.offset_y) / framing.scale], axis=1)
        out[depth <= 1e-6] = np.nan
        return out

    def _box(self, w: np.ndarray, reach: float, framing: Framing, clip: bool) -> tuple[int, int, int, int] | None:
        """The output pixels (x0, y0, x1, y1) the shadow of the card along ``w`` can darken, ``reach`` (world units)
        of penumbra included, below the horizon and on the canvas (or, unclipped, a margin beyond it)."""
        cam = self.camera
        half = 0.5 * cam.n
        depths = [(h - cam.centre[1]) * cam.view[1] - cam.centre[2] * cam.view[2] for h in (0.0, self.height)]
        xs = [(c - half) * d / float(cam.focal) for c in self._x_cols for d in depths]
        ax, az = self._card_axis(w)
        dx, dz = -w[0] / w[1], -w[2] / w[1]
        ray = self._depth_ray()
        deep, ahead = self.depth * ray, -self.front * ray  # its far and near sides (shadows no farther for the drop)
        corners = []
        for x in (min(xs), max(xs)):
            for h in (0.0, self.height):
                gx, gz = x * ax + h * dx, x * az + h * dz
                grow = reach * h / self.height
                for ex, ez in ((0, 0), (grow, 0), (-grow, 0), (0, grow), (0, -grow)):
                    corners += [(gx + ex + d[0], 0.0, gz + ez + d[2]) for d in (np.zeros(3), deep, ahead)]
        uv = self._ground_to_output(np.array(corners), framing)
        width, height = framing.canvas_width, framing.canvas_height
        margin = (UNCLIPPED_MARGIN * width, UNCLIPPED_MARGIN * height) if not clip else (0.0, 0.0)
        lo_x, hi_x = -margin[0], width + margin[0]
        lo_y, hi_y = -margin[1], height + margin[1]
        horizon = (cam.horizon - framing.offset_y) / framing.scale
        lo_y = max(lo_y, math.floor(horizon) + 1.0)
        if np.isnan(uv).any():  # the shadow reaches behind the camera: it runs out of the bottom of the picture
            x0, x1, y1 = lo_x, hi_x, hi_y
            y0 = np.nanmin(uv[:, 1]) if not np.isnan(uv[:, 1]).all() else lo_y
        else:
            (x0, y0), (x1, y1) = uv.min(axis=0), uv.max(axis=0)
        x0, y0 = max(math.floor(x0) - 2, math.floor(lo_x)), max(math.floor(y0) - 2, math.ceil(lo_y))
        x1, y1 = min(math.ceil(x1) + 2, math.ceil(hi_x)), min(math.ceil(y1) + 2, math.ceil(hi_y))
        return (x0, y0, x1, y1) if x1 > x0 and y1 > y0 else None

    def _row_heights(self, source: _Source) -> np.ndarray:
        """The world height above the ground of each source row on the card's centre line."""
        return self._row_geometry(source)[0]

    def _frame_row_geometry(self, rows: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """Per frame row (``rows``): the height above the ground and the camera depth of the card's centre line
        there."""
        cam = self.camera
        # the card's centre line: the frame row of (0, h, 0) is linear-fractional in h; invert it per row
        c, v, up, f = cam.centre, cam.view, cam.up, float(cam.focal)
        k = (np.asarray(rows, np.float64) - 0.5 * cam.n - float(cam.shift)) / f  # row = n/2 + shift - f up / depth
        # up + k depth = 0 with up, depth linear in h: (up_h + k depth_h) h = -(up_0 + k depth_0)
        up0, uph = -c[1] * up[1] - c[2] * up[2], up[1]
        d0, dh = -c[1] * v[1] - c[2] * v[2], v[1]
        h = np.clip(-(up0 + k * d0) / (uph + k * dh), 0.0, self.height)
        return h, d0 + dh * h

    def _sigma_rows(self, source: _Source, w: np.ndarray, angle: float) -> np.ndarray:
        """The blur (sigma, source pixels) of each source row for a disk of ``angle`` degrees along ``w``: half
        the radius D tan(angle / 2) of the disk's footprint on the card, D = h / w_y, in pixels at that height."""
        h, depth = self._row_geometry(source)
        radius_world = h / max(float(w[1]), 1e-3) * math.tan(math.radians(angle) / 2)
        return 0.5 * radius_world * float(self.camera.focal) / depth / source.scale

    def _row_geometry(self, source: _Source) -> tuple[np.ndarray, np.ndarray]:
        """Per source row: the height above the ground and the camera depth of the card's centre line there."""
        return self._frame_row_geometry((np.arange(source.alpha.shape[0]) + 0.5) * source.scale + source.offset_y)

    def _depth_ray(self, height: np.ndarray | float | None = None) -> np.ndarray:
        """The camera's ray through the card's centre line at ``height`` (default: half the card's), scaled to
        a unit horizontal length ((..., 3)): a point this much farther along it lies one world unit deeper
        behind the card (and, looking down, lower)."""
        h = np.asarray(0.5 * self.height if height is None else height, np.float64)
        ray = np.stack([np.zeros_like(h), h, np.zeros_like(h)], axis=-1) - self.camera.centre
        return ray / np.hypot(ray[..., 0], ray[..., 2])[..., None]

    def _depth_lines(
        self, source: _Source, w: np.ndarray, cols: np.ndarray, rows: np.ndarray
    ) -> tuple[np.ndarray, np.ndarray]:
        """At source pixels (``cols``, ``rows``): where (frame pixels, homogeneous, (n, 3)) the card's point the
        pixel shows lies, p0, and how that moves, p1, when what the pixel shows lies one source pixel's worth of
        world units deeper along its own camera ray, through the card's homography: at d such units deeper its
        content lands at (p0 + d p1)[:2] / (p0 + d p1)[2] (looking down, a deeper point near the ground drops
        more than one near the card's top; off the image's centre, it moves sideways too)."""
        ax, az = self._card_axis(w)
        dx, dz = -w[0] / w[1], -w[2] / w[1]
        det = ax * dz - az * dx
        det = det if abs(det) > 1e-9 else 1e-9
        cam = self.camera
        b = self._world_per_pixel * source.scale / self._full.scale  # world units per pixel of this source
        fx = (np.asarray(cols, np.float64) + 0.5) * source.scale + source.offset_x
        fy = (np.asarray(rows, np.float64) + 0.5) * source.scale + source.offset_y
        rays = cam.rays(fx, fy)  # at a unit camera depth
        # where the pixel's ray meets the card's plane (z = 0), t along it, projects back onto the pixel, t deep
        t = -cam.centre[2] / np.where(np.abs(rays[:, 2]) > 1e-12, rays[:, 2], 1e-12)
        p0 = np.stack([t * fx, t * fy, t], axis=1)
        # the ground shift of its shadow, b (r_x + r_y dx, r_z + r_y dz) along the ray r scaled to a unit
        # horizontal length, lands on the card at x = b (dx r_z - dz r_x) / det, h = b (az r_x - det r_y -
        # ax r_z) / det: linear in r, as is its projection (the card's points (x, h, 0) -> frame)
        ray_to_card = b / det * np.array([[-dz, az], [0.0, -det], [dx, -ax]])
        p1 = rays @ (ray_to_card @ cam.projection()[:, :2].T)
        p1 /= np.hypot(rays[:, 0], rays[:, 2])[:, None]
        return p0, p1

    def _depth_steps(self, source: _Source, w: np.ndarray, cols: np.ndarray, rows: np.ndarray) -> np.ndarray:
        """At source pixels (``cols``, ``rows``) ((n, 2), source pixels (x, y)): how far the card's shadow moves
        when what the pixel shows lies one source pixel's worth of world units deeper (:meth:`_depth_lines`)."""
        p0, p1 = self._depth_lines(source, w, cols, rows)
        return (_landing(p0, p1, np.ones(len(p0))) - _landing(p0, p1, np.zeros(len(p0)))).T / source.scale

    def _step_cells(self, source: _Source, w: np.ndarray, k: int, depth: float) -> tuple[list[Cell], np.ndarray]:
        """For a copy of the source reduced ``k`` times, swept to ``depth`` (its pixels, either side of the card):
        its cells (r0, r1, c0, c1, step), over each of which one depth step (:meth:`_depth_steps`, at the cell's
        centre) draws a segment of depth within ``STEP_TOLERANCE`` pixels of where each pixel's own step puts it
        (at most ``MAX_STEP_CELLS`` down and across), and the steps at the copy's corners and between (they bound
        the others)."""
        h, wd = source.alpha.shape
        probe = np.linspace(0.0, 1.0, 5)
        pc, pr = np.meshgrid(probe * (wd - 1), probe * (h - 1))
        grid = self._depth_steps(source, w, pc.ravel(), pr.ravel()).reshape(5, 5, 2)
        spread = np.array([np.ptp(grid, axis=axis).max() for axis in (0, 1)]) * k / STEP_TOLERANCE  # down, along
        n_r, n_c = (
            min(max(math.ceil(float(x) * depth), 1), most) for x, most in zip(spread, MAX_STEP_CELLS, strict=True)
        )
        rb = np.linspace(0, h, n_r + 1).round().astype(int)
        cb = np.linspace(0, wd, n_c + 1).round().astype(int)
        cc, rr = np.meshgrid(0.5 * (cb[:-1] + cb[1:]), 0.5 * (rb[:-1] + rb[1:]))
        steps = self._depth_steps(source, w, cc.ravel(), rr.ravel()).reshape(n_r, n_c, 2)
        rb, cb = -(-rb // k), -(-cb // k)  # on the reduced copy
        cells = [
            (int(rb[i]), int(rb[i + 1]), int(cb[j]), int(cb[j + 1]), steps[i, j])
            for i in range(n_r)
            for j in range(n_c)
            if rb[i + 1] > rb[i] and cb[j + 1] > cb[j]
        ]
        return cells, grid.reshape(-1, 2)

    def _swept(
        self, card: np.ndarray, source: _Source, w: np.ndarray, soft: np.ndarray, k: int
    ) -> tuple[np.ndarray, tuple[int, int]]:
        """The card (uint8, blurred) swept through the object's depth (:func:`_swept_card`): each pixel repeated
        along its own shift with depth (:meth:`_depth_steps`) from its surface's depth to its far end (fading out
        over ``soft`` pixels of depth given per row, as blurred as the card's row), on a copy reduced ``k`` times
        (:func:`_sweep_reduction`; k > 1: without the card itself at full resolution); and the (x, y) in the
        result's pixels of the card's pixel (0, 0)."""
        near, far = self._sweep_depths(source, k)
        cells, steps = self._step_cells(source, w, k, max(float(far.max()), -float(near.min())))

        def lines(rows: np.ndarray, cols: np.ndarray) -> tuple[np.ndarray, np.ndarray]:  # in the reduced copy
            p0, p1 = self._depth_lines(source, w, cols * k + 0.5 * (k - 1), rows * k + 0.5 * (k - 1))
            unit = 1.0 / (source.scale * k)
            return p0 * [unit, unit, 1.0], p1 * [k * unit, k * unit, k]

        if k > 1:
            h, wd = card.shape
            card = np.asarray(Image.fromarray(np.pad(card, ((0, -h % k), (0, -wd % k))), "L").reduce(k))
            soft = soft[::k][: card.shape[0]] / k
        return _swept_card(card, near, far, soft, cells, steps, lines)

    def _sweep_depths(self, source: _Source, k: int) -> tuple[np.ndarray, np.ndarray]:
        """How deep (pixels of the copy of ``source`` reduced ``k`` times that its depth is swept on) behind the
        card each of its pixels' surface lies and how deep the object reaches there, looking down no deeper
        along the ray than where the ray meets the ground (made once per source and k)."""
        key = (round(source.scale / self._full.scale), k)
        if key not in self._swept_depths:
            near, far = (d[key[0]][::k, ::k] for d in (self._near, self._far))
            above = self._above(source)[::k]
            self._swept_depths[key] = (
                np.minimum(near, above).astype(np.float32) / k,
                np.minimum(far, above).astype(np.float32) / k,
            )
        return self._swept_depths[key]

    def _above(self, source: _Source) -> np.ndarray:
        """(rows, 1) per row of ``source``: how deep (its pixels) a point can lie behind the card along the
        camera's ray before that ray meets the ground, or, where the object floats, the height of its lowest
        point (:attr:`_floor`): no part of it lies lower."""
        heights = self._row_heights(source)
        k = round(source.scale / self._full.scale)
        drop = np.maximum(0.0, -self._depth_ray(heights)[:, 1]) * self._world_per_pixel * k  # per pixel of depth
        return (np.maximum(heights - self._floor, 0.0) / np.maximum(drop, 1e-9))[:, None]

    def _at_card(self, card: np.ndarray, source: _Source) -> np.ndarray:
        """``card`` (of ``source``) where its pixels' surfaces lie within a pixel behind the card or in front of
        it (their spans reach the card's plane: a part in front reaches back to it), all of it where every one
        does."""
        k = round(source.scale / self._full.scale)
        if k not in self._on_card:  # 1 where the pixel's surface lies on the card, 0 where off it
            on = np.less(self._near[k], 1.0)
            on[self._above(source)[:, 0] < 1.0] = True  # a row whose ray meets the ground within a pixel
            self._on_card[k] = None if on.all() else on.view(np.uint8)
        on = self._on_card[k]
        return card if on is None else np.multiply(card, on, dtype=np.uint8)

    def _surface_depth(self, feet: np.ndarray, framing: Framing, y0: int, base: float) -> np.ndarray:
        """How deep (pixels of ``alpha``) behind the card each pixel's surface lies, from its foot's row
        (``feet``, rows of ``alpha``, whose row 0 lies at canvas row ``y0``): the ground's distance from the
        camera at the foot's row less at the card's foot (frame row ``base``), along the card's depth ray (negative
        where the foot lies nearer: a surface in front of the card), at most ``MAX_SURFACE_DEPTH`` times the
        cutout's size either way."""
        cam, s = self.camera, framing.scale
        h, w = feet.shape
        k = max(1, math.ceil(max(h, w) / DEPTH_SIZE))  # worked out on a reduced copy (it is smooth) and enlarged
        lowest = cam.horizon + HORIZON_GAP * cam.n  # a foot nearer the horizon than this lies this near it
        rows = np.maximum((np.asarray(feet[::k, ::k], np.float64) + y0) * s + framing.offset_y, lowest)
        ahead = ground_ahead(self.camera, rows) - ground_ahead(self.camera, np.array([max(base, lowest)]))[0]
        along = abs(float(self._depth_ray() @ FORWARD))  # the depth ray's unit horizontal length, ahead
        most = MAX_SURFACE_DEPTH * max(h, w)
        pixels = np.clip(ahead / max(along, 1e-9) / self._world_per_pixel, -most, most)
        return _enlarged(pixels, k, (h, w))

    def _mid_depth(self) -> float:
        """The camera depth of the card's centre line at half its height."""
        cam = self.camera
        return float((0.5 * self.height - cam.centre[1]) * cam.view[1] - cam.centre[2] * cam.view[2])

    # -- the shadow -----------------------------------------------------------------------------------------------
    def shadow(
        self, u: float, v: float, angle: float, framing: Framing, clip: bool = True
    ) -> tuple[np.ndarray, int, int]:
        """The shadow s of a disk light at map point (u, v), ``angle`` degrees across, on ``framing``'s canvas.

        Returns
        -------
        values, x, y
            (h, w) float32 values in [0, 1] whose top-left pixel lies at output pixel (x, y); (0, 0) values
            when the card casts nothing onto the visible ground.
        """
        empty = (np.zeros((0, 0), np.float32), 0, 0)
        w = light_direction(u, v)
        if self.empty or w[1] <= 1e-4:
            return empty
        reach = self.height / w[1] * math.tan(math.radians(angle) / 2)
        box = self._box(w, reach, framing, clip)
        if box is None:
            return empty
        x0, y0, x1, y1 = box
        # an output coarser than the cutout (a preview) is traced at up to ``SUPERSAMPLE`` times its resolution
        # and averaged down: Pillow's resampling does not antialias, and a crisp edge would alias
        fine = max(1, min(SUPERSAMPLE, int(framing.scale / self._full.scale + 1e-6)))
        source = self._source(framing.scale / fine)
        sigma_rows = self._sigma_rows(source, w, angle)
        card = self._blurred(source, sigma_rows)
        to_card = self._homography(w, framing, source, (x0, y0)) @ np.diag([1.0 / fine, 1.0 / fine, 1.0])
        size = ((x1 - x0) * fine, (y1 - y0) * fine)
        if self.depth > 0 or self.front > 0:
            k = _sweep_reduction(card, sigma_rows)
            fade = 2.0 * sigma_rows  # where a pixel's depth ends: as blurred as its row (a short one drawn crisp)
            swept, (sx, sy) = self._swept(card, source, w, np.where(fade < MIN_FADE, 0.0, fade), k)
            values = _warp(swept, np.array([[1.0 / k, 0, sx], [0, 1.0 / k, sy], [0, 0, 1.0]]) @ to_card, size)
            if k > 1:  # swept on a reduced copy: the card itself, crisp, where that copy's shadow is partial
                values = _warp(self._at_card(card, source), to_card, size, values, within=True)
        else:
            values = _warp(card, to_card, size)
        if fine > 1:
            values = values.reshape(y1 - y0, fine, x1 - x0, fine).mean(axis=(1, 3))
        return values, x0, y0


def _sweep_reduction(card: np.ndarray, sigma_rows: np.ndarray) -> int:
    """How many times smaller a copy of ``card`` the depth is swept on: about ``SWEEP_SIZE`` pixels at most, and
    a pixel as wide as the blur of most of its rows (``sigma_rows``, pixels; a soft light's copy needs no finer)."""
    rows = np.flatnonzero(card.any(axis=1))
    blur = float(np.percentile(sigma_rows[rows], SWEEP_BLUR_SHARE)) if rows.size else 0.0
    return max(1, math.ceil(max(card.shape) / SWEEP_SIZE), int(blur))


def _swept_card(
    card: np.ndarray,
    near: np.ndarray,
    far: np.ndarray,
    soft: np.ndarray,
    cells: list[Cell],
    steps: np.ndarray,
    lines: Callable[[np.ndarray, np.ndarray], tuple[np.ndarray, np.ndarray]],
) -> tuple[np.ndarray, tuple[int, int]]:
    """``card`` (uint8) with each pixel repeated at ``-step * d`` for every depth d from ``near`` to ``far``
    there (pixels), then fading linearly to nothing over ``soft`` pixels of depth (given per row: where the
    shadow ends, as blurred as the card's row; in steps of at most ``FADE_STEP`` pixels of shift); and the (x, y)
    of the card's pixel (0, 0) in the result.
    ``lines(rows, cols)`` gives where pixels' copies lie ((n, 3) p0 and p1: at depth d, at
    (p0 + d p1)[:2] / (p0 + d p1)[2], pixels of ``card``), which places each copy's start; it reaches on along
    the step of the cell (r0, r1, c0, c1, step) of ``cells`` the pixel lies in; ``steps`` ((n, 2)) bound every
    step.

    A pixel's span is drawn as one or two copies of a segment a power of two long in depth (:func:`_segments`),
    so that it starts and ends where its own depths say, whatever the other pixels' spans; each length's copies,
    cell by cell, are scattered at their starts and the segment drawn once over them all (the segment's max
    commutes with the max over its copies)."""
    top = float(far.max())
    h, wd = card.shape
    lit = np.flatnonzero(card)
    if lit.size == 0:
        return np.zeros((1, 1), np.uint8), (0, 0)
    cell = np.zeros(card.shape, np.int16)  # which cell each pixel lies in
    for i, (r0, r1, c0, c1, _) in enumerate(cells):
        cell[r0:r1, c0:c1] = i
    longest = max(float(np.hypot(*step)) for *_, step in cells)
    unit = 1.0 / longest if longest > 1e-9 else max(top, 1.0)  # depth shifting a copy by a pixel at most
    rows, cols = np.divmod(lit, wd)
    value = card.ravel()[lit]
    n, f = near.ravel()[lit], far.ravel()[lit]
    fade = np.minimum(np.broadcast_to(np.maximum(soft, 0.0)[:, None], card.shape).ravel()[lit], top - f)
    # each span [n, f] drawn whole, then its fade [f, f + fade] in steps of falling value, each at most
    # FADE_STEP pixels of shift long (a linear fade's staircase too fine to see), where the fade is a pixel or more
    faded = np.flatnonzero(fade >= unit)
    count = np.minimum(np.ceil(fade[faded] / (FADE_STEP * unit)), MAX_FADE_STEPS)  # each fading pixel's steps
    first, j, of = _segments(n, f, unit)
    copies = [(first, j, of, value[of])]
    # a fade's step: one copy from its start, at least as long (the next step is paler)
    for m in range(int(count.max(initial=0))):
        now = count > m
        pixel, parts = faded[now], count[now]
        a, b = (f[pixel] + fade[pixel] * (x / parts) for x in (m, m + 1))
        j = np.ceil(np.log2(np.maximum(b - a, unit) / unit)).astype(np.int64)
        copies.append((a, j, pixel, (value[pixel] * (1.0 - (m + 0.5) / parts)).astype(np.uint8)))
    starts, lengths, which, values = (np.concatenate(x) for x in zip(*copies, strict=True))
    p0, p1 = lines(rows.astype(np.float64), cols.astype(np.float64))
    # where each copy starts (pixels of the card, rounded): its pixel's content at the copy's start depth
    a0, b0, c0, a1, b1, c1 = (x[which] for x in (*p0.T.astype(np.float32), *p1.T.astype(np.float32)))
    depth = starts.astype(np.float32)
    at = c0 + depth * c1
    ix = cols[which] + np.rint(a0 / c0 - (a0 + depth * a1) / at).astype(np.int32)
    iy = rows[which] + np.rint(b0 / c0 - (b0 + depth * b1) / at).astype(np.int32)
    # kept within the card's size beyond where the steps at depth 0 would take the deepest and the nearest (the
    # card's top seen from a low sun can project towards the horizon)
    reach = np.concatenate([-np.asarray(steps) * top, -np.asarray(steps) * min(float(near.min()), 0.0)])
    lo_cap = np.floor(np.minimum(reach.min(axis=0), 0)).astype(int) - (wd, h)
    hi_cap = np.ceil(np.maximum(reach.max(axis=0), 0)).astype(int) + (2 * wd, 2 * h)
    kept = (ix >= lo_cap[0]) & (ix < hi_cap[0]) & (iy >= lo_cap[1]) & (iy < hi_cap[1])
    lengths, which, values, ix, iy = (x[kept] for x in (lengths, which, values, ix, iy))
    key = (cell.ravel()[lit][which] * 64 + lengths).astype(np.int16)  # (sorted by radix)
    order = np.argsort(key, kind="stable")
    bounds = np.flatnonzero(np.diff(key[order], prepend=-1, append=-1))
    groups = []  # each segment's copies: their starts (x, y), their values, the segment, their box x0, y0, x1, y1
    for a, b in zip(bounds[:-1], bounds[1:], strict=True):
        group = order[a:b]
        c, j = divmod(int(key[group[0]]), 64)
        span = -cells[c][4] * unit * 2.0**j
        gx, gy = ix[group], iy[group]
        box = (int(gx.min()), int(gy.min()), int(gx.max()) + 1, int(gy.max()) + 1)
        groups.append((gx, gy, values[group], span, box))
    boxes = np.array([g[4] for g in groups] + [(0, 0, wd, h)], float)
    reaches = np.array([g[3] for g in groups] + [(0.0, 0.0)])  # each segment's, from its copies' starts
    lo = np.floor(np.minimum(boxes[:, :2], boxes[:, :2] + reaches).min(axis=0)).astype(int) - 1
    hi = np.ceil(np.maximum(boxes[:, 2:], boxes[:, 2:] + reaches).max(axis=0)).astype(int) + 1
    out = np.zeros((hi[1] - lo[1], hi[0] - lo[0]), np.uint8)
    for gx, gy, v, span, (x0, y0, x1, y1) in groups:
        placed = np.zeros((y1 - y0, x1 - x0), np.uint8)
        np.maximum.at(placed, (gy - y0, gx - x0), v)
        _sweep_into(out, placed, np.array([x0, y0]) - lo, span)
    return out, (int(-lo[0]), int(-lo[1]))


def _landing(p0: np.ndarray, p1: np.ndarray, depths: np.ndarray) -> np.ndarray:
    """(2, n): where content at ``depths`` lands on lines p0 + d p1 (homogeneous, (n, 3))."""
    p = p0 + depths[:, None] * p1
    return p[:, :2].T / p[:, 2]


def _segments(start: np.ndarray, end: np.ndarray, unit: float) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Spans [start, end] (depths) as segments ``unit`` * 2^j long: each span at least ``unit`` long by two
    copies of the longest that fits it, one from its start and one ending at its end (together exactly the
    span); a shorter one by one ``unit`` long from its start. Returns each copy's start, j and span (index)."""
    length = np.maximum(end - start, 0.0)
    j = np.floor(np.log2(np.maximum(length, unit) / unit)).astype(np.int64)
    long = np.flatnonzero(length >= unit)
    index = np.concatenate([np.arange(start.size), long])
    starts = np.concatenate([start, end[long] - unit * 2.0 ** j[long]])
    return starts, j[index], index


def _sweep_into(out: np.ndarray, part: np.ndarray, origin: np.ndarray, span: np.ndarray) -> None:
    """``out`` = max(``out``, ``part`` placed at ``origin`` + t ``span`` for t in [0, 1]), the segment made by
    doubling (log2 of its length in pixels copies)."""
    length = float(np.hypot(*span))
    n = max(1, math.ceil(length))
    unit = span / n if length > 0 else np.zeros(2)
    shifts, covered = [], 1  # each doubling's shift: the copies so far moved by it cover twice as many offsets
    while covered < n:
        add = min(covered, n - covered)
        shifts.append(np.round(unit * add).astype(int))
        covered += add
    steps = np.array(shifts, int).reshape(-1, 2)
    off = np.minimum(steps, 0).sum(axis=0)  # where, from ``origin``, the swept part's box starts
    h, w = part.shape
    size = np.array([w, h]) + np.abs(steps).sum(axis=0)
    swept = np.zeros((size[1], size[0]), np.uint8)  # one buffer; each doubling maxes its filled box, shifted, in
    at = -off  # part's corner in ``swept``, then the filled box's
    swept[at[1] : at[1] + h, at[0] : at[0] + w] = part
    for d in steps:
        src = swept[at[1] : at[1] + h, at[0] : at[0] + w]
        dst = swept[at[1] + d[1] : at[1] + d[1] + h, at[0] + d[0] : at[0] + d[0] + w]
        np.maximum(dst, src, out=dst)  # (overlapping views: numpy reads a copy of ``src``)
        at, h, w = np.minimum(at, at + d), h + abs(int(d[1])), w + abs(int(d[0]))
    at = origin + off
    y0, x0 = max(0, at[1]), max(0, at[0])
    y1, x1 = min(out.shape[0], at[1] + swept.shape[0]), min(out.shape[1], at[0] + swept.shape[1])
    if y1 > y0 and x1 > x0:
        view = out[y0:y1, x0:x1]
        np.maximum(view, swept[y0 - at[1] : y1 - at[1], x0 - at[0] : x1 - at[0]], out=view)


def _warp(
    card: np.ndarray, hmat: np.ndarray, size: tuple[int, int], under: np.ndarray | None = None, within: bool = False
) -> np.ndarray:
    """The (height, width) output of the homography ``hmat`` (output to ``card`` coordinates, continuous; any
    scale) of ``card`` (uint8), as float32 in [0, 1]: only the output pixels that can map into the card's
    non-zero part (:func:`_slab_outlines`) are resampled, a band of ``BAND`` rows at a time, on the machine's
    cores; where ``under`` is given ((height, width) float32), the larger of it and the warp, in it.
    ``within``: the warp lies within ``under``'s non-zero part, so only the columns of a band where ``under``
    is neither 0 nor 1 are resampled (and a pixel or two around)."""
    hmat = hmat / hmat[2, 2]
    width, height = size
    out = np.zeros((height, width), np.float32) if under is None else under
    outlines = _slab_outlines(card, hmat, size)
    if not outlines:
        return out
    row_lo, row_hi = _row_columns(outlines, height)
    image = Image.fromarray(card, "L")

    def band(stripe: slice) -> None:
        for r0 in range(stripe.start, stripe.stop, BAND):
            r1 = min(r0 + BAND, stripe.stop)
            lo, hi = float(row_lo[r0 : r1 + 1].min()), float(row_hi[r0 : r1 + 1].max())
            if hi < lo:
                continue
            c0, c1 = max(0, math.floor(lo) - 1), min(width, math.ceil(hi) + 2)
            if c1 <= c0:
                continue
            for a, b in _partial_runs(out[r0:r1, c0:c1], c0, width) if within else [(c0, c1)]:
                shift = np.array([[1.0, 0.0, a], [0.0, 1.0, r0], [0.0, 0.0, 1.0]])
                local = hmat @ shift
                local = local / local[2, 2]
                part = image.transform(
                    (b - a, r1 - r0), Image.Transform.PERSPECTIVE, tuple(local.ravel()[:8]), Image.Resampling.BILINEAR
                )
                values = np.asarray(part, np.float32) * np.float32(1 / 255)
                np.maximum(out[r0:r1, a:b], values, out=out[r0:r1, a:b])

    for_each_stripe(band, 0, height, width)
    return out


def _partial_runs(under: np.ndarray, start: int, width: int) -> list[tuple[int, int]]:
    """The column runs [a, b) (offset by ``start``, within ``width``) where some row of ``under`` lies strictly
    between 0 and 1, widened by ``RUN_MARGIN`` and joined across gaps shorter than ``RUN_GAP``."""
    used = ((under > 0) & (under < 1)).any(axis=0)
    edges = np.flatnonzero(np.diff(used, prepend=False, append=False))
    runs: list[tuple[int, int]] = []
    for a, b in zip(edges[::2] + start - RUN_MARGIN, edges[1::2] + start + RUN_MARGIN, strict=True):
        if runs and a - runs[-1][1] < RUN_GAP:
            runs[-1] = (runs[-1][0], int(b))
        else:
            runs.append((int(a), int(b)))
    return [(max(0, a), min(width, b)) for a, b in runs]


def _slab_outlines(card: np.ndarray, hmat: np.ndarray, size: tuple[int, int]) -> list[np.ndarray]:
    """Where ``card``'s non-zero pixels can lie on the ``size`` (w, h) output of the homography ``hmat`` (output
    to card): the output polygons (k, 2) of the boxes of its non-zero part in ``SLABS`` bands of rows (a tall
    card's shadow is a slanted strip its bounding box would cover many times over), each cut where it would
    reach beyond the horizon or behind the camera (its shadow runs off the output there)."""
    rows = np.flatnonzero(card.any(axis=1))
    if rows.size == 0:
        return []
    inverse = np.linalg.inv(hmat)
    side = math.copysign(1.0, float(hmat[2] @ [0.5 * size[0], 0.5 * size[1], 1.0]))  # w's sign on the output
    outlines = []
    edges = np.linspace(rows[0], rows[-1] + 1, SLABS + 1).round().astype(int)
    for a, b in zip(edges[:-1], edges[1:], strict=True):
        cols = np.flatnonzero(card[a:b].any(axis=0)) if b > a else np.zeros(0, int)
        if cols.size == 0:
            continue
        box = np.array(
            [[cols[0] - 1, a - 1, 1], [cols[-1] + 2, a - 1, 1], [cols[-1] + 2, b + 1, 1], [cols[0] - 1, b + 1, 1]],
            float,
        )
        mapped = box @ inverse.T
        reach = side * mapped[:, 2] - MIN_W * np.abs(mapped[:, 2]).max()
        kept = []
        for i in range(4):  # the box's part in front of the camera (Sutherland-Hodgman, one edge)
            j = (i + 1) % 4
            if reach[i] >= 0:
                kept.append(mapped[i])
            if (reach[i] >= 0) != (reach[j] >= 0):
                kept.append(mapped[i] + (mapped[j] - mapped[i]) * reach[i] / (reach[i] - reach[j]))
        if kept:
            points = np.array(kept)
            outlines.append(points[:, :2] / points[:, 2:])
    return outlines


def _row_columns(outlines: list[np.ndarray], height: int) -> tuple[np.ndarray, np.ndarray]:
    """For each output row line y = 0 .. ``height``: the least and the most x that the convex polygons
    ``outlines`` (each (k, 2)) reach on it or between it and the next (inf and -inf where they do not)."""
    start = np.concatenate(outlines)
    end = np.concatenate([np.roll(outline, -1, axis=0) for outline in outlines])
    y = np.arange(height + 1, dtype=float)[:, None]
    with np.errstate(divide="ignore", invalid="ignore"):
        t = (y - start[:, 1]) / (end[:, 1] - start[:, 1])
    crossing = (t >= 0) & (t <= 1)
    x = start[:, 0] + np.where(crossing, t, 0.0) * (end[:, 0] - start[:, 0])
    lo, hi = np.where(crossing, x, np.inf).min(axis=1), np.where(crossing, x, -np.inf).max(axis=1)
    row = np.floor(start[:, 1])
    inside = (row >= 0) & (row <= height)
    np.minimum.at(lo, row[inside].astype(int), start[inside, 0])
    np.maximum.at(hi, row[inside].astype(int), start[inside, 0])
    return lo, hi


def _blur(alpha: np.ndarray, sigma: float) -> np.ndarray:
    """``alpha`` (float32 in [0, 1]) blurred by a Gaussian of ``sigma`` pixels (Pillow's, in 8 bits, on a copy
    reduced so that the blur spans at most ``WIDE_BLUR`` of its pixels, enlarged back), zeros beyond its edges."""
    h, w = alpha.shape
    reduce = max(1, int(sigma // WIDE_BLUR))
    pad = int(math.ceil(3 * sigma / reduce)) + 1
    size = (max(1, w // reduce), max(1, h // reduce))
    image = Image.fromarray(np.round(alpha * 255).astype(np.uint8), "L")
    if reduce > 1:
        image = image.resize(size, Image.Resampling.BOX)
    padded = Image.new("L", (size[0] + 2 * pad, size[1] + 2 * pad), 0)
    padded.paste(image, (pad, pad))
    # cropped as an array: Pillow's crop would apply its decompression-bomb limit to our own buffers
    blurred = np.asarray(padded.filter(ImageFilter.GaussianBlur(sigma / reduce)))[
        pad : pad + size[1], pad : pad + size[0]
    ]
    if reduce > 1:
        blurred = np.asarray(
            Image.fromarray(np.ascontiguousarray(blurred), "L").resize((w, h), Image.Resampling.BILINEAR)
        )
    return np.asarray(blurred, np.float32) * np.float32(1 / 255)


BAND_RISE = 0.03  # share of the cutout's height the contact line may rise within one card
MAX_BANDS = 12
MAX_CONTACT_SLOPE = 1.0  # rows per column: a steeper contact line is no ground
FOOTPRINT_DEPTH = 1.0  # a footprint reaches back from its front point at most this many times as far as sideways
RAMP = 0.5  # share of the narrower band over which two neighbouring cards cross-fade


def contact_line(alpha: np.ndarray, max_rise: float | None = None) -> np.ndarray:
    """The ground contact row of each column (float, nan where the cutout has no column): the lower convex hull
    of the cutout's lowest solid pixels, so that parts standing farther back (higher in the picture) stand on
    the ground there, and a gap between legs spans from foot to foot. From the lowest point outwards, a hull
    steeper than ``MAX_CONTACT_SLOPE`` is no ground (a tail): the line stays level beyond; and it rises above
    the lowest point by at most ``max_rise`` rows per column of distance from it (:func:`footprint_rise`: what a
    footprint on the ground can show the camera; a round body's underside rises faster)."""
    solid = alpha > SOLID
    cols = np.flatnonzero(solid.any(axis=0))
    if cols.size == 0:
        return np.full(alpha.shape[1], np.nan)
    bottoms = alpha.shape[0] - np.argmax(solid[::-1, cols], axis=0)  # one past the lowest solid row
    hull: list[tuple[float, float]] = []
    for x, y in zip(cols.astype(float), bottoms.astype(float), strict=True):
        while len(hull) >= 2:
            (xa, ya), (xb, yb) = hull[-2], hull[-1]
            if (xb - xa) * (y - ya) - (yb - ya) * (x - xa) >= 0:  # b lies above the chord a-(x, y): not on the hull
                hull.pop()
            else:
                break
        hull.append((x, y))
    hx, hy = np.array(hull).T
    low = int(np.argmax(hy))
    for step in (1, -1):
        k = low
        while 0 <= k + step < hx.size and abs(hy[k + step] - hy[k]) <= MAX_CONTACT_SLOPE * abs(hx[k + step] - hx[k]):
            k += step
        end = slice(k + 1, None) if step == 1 else slice(None, k)
        hy[end] = hy[k]
    line = np.full(alpha.shape[1], np.nan)
    xs = np.arange(cols[0], cols[-1] + 1)
    line[cols[0] : cols[-1] + 1] = np.interp(xs, hx, hy)
    if max_rise is not None:
        np.maximum(line[xs], hy[low] - max_rise * np.abs(xs - hx[low]), out=line[cols[0] : cols[-1] + 1])
    return line


def footprint_rise(alpha: np.ndarray, framing: Framing, camera: tuple[float, float] | None) -> float | None:
    """How many rows per column a footprint's outline can rise from its lowest point under ``camera`` (as
    :class:`CardTracer`'s): a footprint reaching back ``FOOTPRINT_DEPTH`` times as far as sideways (a round one
    reaches back as far) is foreshortened by sin(e) where the camera looks down on the ground by e. A camera
    looking along the ground sees every footprint nearly level, and a ball's rising underside as no ground."""
    rows = np.flatnonzero((alpha > ROWS_ALPHA).any(axis=1))
    solid = np.flatnonzero((alpha > SOLID).any(axis=1))
    if rows.size == 0 or solid.size == 0:
        return None
    s, oy = framing.scale, framing.offset_y + framing.bbox[1] * framing.scale
    horizon, focal = camera if camera is not None else (None, None)
    base = (solid[-1] + 1) * s + oy  # the frame row of the lowest solid pixel's foot
    cam, _ = camera_for_span(framing.n, rows[0] * s + oy, base, horizon, focal)
    ray = cam.rays(0.5 * cam.n, base)
    return FOOTPRINT_DEPTH * max(0.0, -float(ray[1])) / float(np.linalg.norm(ray))


def contact_bands(alpha: np.ndarray, max_rise: float | None = None) -> list[tuple[int, int, int]]:
    """Column bands (c0, c1, foot) of the cutout over which its contact line (:func:`contact_line`, rising at
    most ``max_rise``) rises by at most ``BAND_RISE`` of its height (at most ``MAX_BANDS`` bands); ``foot`` is
    the band's lowest contact row."""
    line = contact_line(alpha, max_rise)
    cols = np.flatnonzero(np.isfinite(line))
    if cols.size == 0:
        return []
    rows = np.flatnonzero((alpha > ROWS_ALPHA).any(axis=1))
    span = np.nanmax(line) - np.nanmin(line)
    tol = max(2.0, BAND_RISE * (rows[-1] + 1 - rows[0]), span / MAX_BANDS)
    bands, start = [], int(cols[0])
    lo = hi = line[start]
    for c in range(start + 1, int(cols[-1]) + 1):
        lo, hi = min(lo, line[c]), max(hi, line[c])
        if hi - lo > tol:
            bands.append((start, c, int(math.ceil(np.max(line[start:c])))))
            start, lo, hi = c, line[c], line[c]
    bands.append((start, int(cols[-1]) + 1, int(math.ceil(np.max(line[start : int(cols[-1]) + 1])))))
    return bands


def depth_map(alpha: np.ndarray) -> np.ndarray:
    """How deep (pixels) the object reaches behind its card at each pixel: a round cross-section. A pixel at
    distance d from the outline, inside a part whose largest inscribed disk holding it has radius R (its local
    radius, :func:`local_radius`: a leg's half-width, a body's half-height), reaches the chord of a circle of
    radius R there, 2 sqrt(2 R d - d^2): as deep as the part is wide at its middle, steep at its edges (a disk
    is a sphere's chords). Computed on a copy reduced to about ``DEPTH_SIZE`` pixels and enlarged; pixels of the
    antialiased fringe take their nearest solid pixel's depth."""
    h, w = alpha.shape
    k = max(1, math.ceil(max(h, w) / DEPTH_SIZE))
    small = np.asarray(Image.fromarray(np.asarray(alpha, np.float32), "F").reduce(k)) if k > 1 else alpha
    solid = np.pad(small > SOLID, 1)  # the outline continues beyond the array's edges
    if not solid.any():
        return np.zeros(alpha.shape, np.float32)
    d = np.asarray(ndimage.distance_transform_edt(solid), np.float32)
    depth = 2.0 * k * np.sqrt(np.maximum(0.0, d * (2.0 * local_radius(d) - d)))
    return _enlarged(nearest_fill(depth, solid)[1:-1, 1:-1], k, (h, w))


def local_radius(d: np.ndarray) -> np.ndarray:
    """Each pixel's local radius from ``d`` (float32, its distance to the outline; 0 outside): the radius of the
    largest disk inside the outline that holds it, d(c) of the centre c with |p - c| <= d(c) for which that is
    largest, at least the pixel's own d. The disks are painted from their centres (the pixels no neighbour's
    disk nearly holds, ``RIDGE_RISE``: the outline's ridge), each over its bounding box (a pixel near a corner,
    held by no ridge pixel's disk, keeps its own d)."""
    h, w = d.shape
    padded = np.pad(d, 1)
    ridge = d > 0
    for dy, dx in ((-1, -1), (-1, 0), (-1, 1), (0, -1), (0, 1), (1, -1), (1, 0), (1, 1)):
        ridge &= padded[1 + dy : 1 + dy + h, 1 + dx : 1 + dx + w] < d + RIDGE_RISE * math.hypot(dx, dy)
    radius = d.copy()
    ys, xs = np.nonzero(ridge)
    for y, x in zip(ys.tolist(), xs.tolist(), strict=True):
        r = float(d[y, x])
        y0, y1, x0, x1 = max(0, y - int(r)), min(h, y + int(r) + 1), max(0, x - int(r)), min(w, x + int(r) + 1)
        dist2 = (np.arange(y0, y1)[:, None] - y) ** 2 + (np.arange(x0, x1)[None, :] - x) ** 2
        view = radius[y0:y1, x0:x1]
        np.maximum(view, np.where(dist2 <= r * r, np.float32(r), np.float32(0)), out=view)
    return radius


def read_thickness(alpha: np.ndarray, depth: np.ndarray) -> float:
    """The thickness the outline reads as (conventions, "Lift and thickness"): the deepest point of ``depth``
    (:func:`depth_map`) over the width of the cutout's solid part; 1 for a disk, 0 where nothing is solid."""
    cols = np.flatnonzero((alpha > SOLID).any(axis=0))
    if cols.size == 0:
        return 0.0
    return float(depth.max()) / float(cols[-1] + 1 - cols[0])


def _band_card(
    part: np.ndarray,
    framing: Framing,
    camera: tuple[float, float] | None,
    origin: tuple[int, int],
    foot: int,
    thickness: np.ndarray | None,
    feet: np.ndarray | None,
    far_feet: np.ndarray | None,
    given_thickness: float | None,
    kept: Kept | None,
    relief: float,
    lift: int,
    at_rest: SurfaceDepths | None = None,
) -> CardTracer:
    """The card of one band of a cutout (:class:`ContactTracer`) whose foot moves ``lift`` rows down (its share of
    the object's lift, :func:`rigid_lifts`): its foot and every pixel's foot that many rows lower (not worked out
    where ``at_rest`` gives the surfaces: the card reads no feet then); ``relief``: the share of its read depth
    the object keeps."""
    shift = np.float32(lift)
    if at_rest is not None:
        feet = far_feet = None
    return CardTracer(
        part,
        framing,
        camera,
        origin=origin,
        foot=foot + lift,
        thickness=thickness,
        feet=None if feet is None else feet + shift,
        far_feet=None if far_feet is None else far_feet + shift,
        lift=lift,
        at_rest=at_rest,
        given_thickness=given_thickness,
        kept=kept,
        relief=relief,
    )


def ground_ahead(camera: Camera, rows: np.ndarray) -> np.ndarray:
    """Where along the forward axis (world units; 0 at the card's foot, as ``camera`` is placed) the ground lies
    at frame ``rows`` (below the horizon; the same along a row, the camera having no roll)."""
    rays = camera.rays(np.full(rows.shape, 0.5 * camera.n), rows)
    t = -camera.centre[1] / np.minimum(rays[..., 1], -1e-12)
    return (camera.centre + t[..., None] * rays) @ FORWARD


def ground_rows(camera: Camera, ahead: np.ndarray) -> np.ndarray:
    """The frame rows at which the ground lies at ``ahead`` along the forward axis (:func:`ground_ahead`'s
    inverse)."""
    below = camera.centre * np.array([1.0, 0.0, 1.0])  # the ground point straight below the camera
    points = below + (np.asarray(ahead, np.float64) - below @ FORWARD)[:, None] * FORWARD
    return camera.project(points)[:, 1]


def rigid_lifts(camera: Camera, feet: np.ndarray, lowest: float, foot: float, lift: float) -> np.ndarray:
    """The rows each foot (``feet``, frame rows of ground points on ``camera``'s image) of an object moves down when
    it floats ``lift`` rows (conventions, "Lift and thickness"): the object's lowest pixel (frame row ``lowest``)
    shows a surface whose foot lay at frame row ``foot`` as it stood, and ``lift`` rows below it as it floats. The
    floating object shows the same image as the one read standing, so it is that object scaled about the camera's
    centre by the share that moves that foot so: every foot's ground point comes that share as far from the camera,
    and a foot farther back moves by fewer rows (a uniform shift would lift it higher in the world)."""
    feet = np.asarray(feet, np.float64)
    here = float(camera.centre @ FORWARD)  # (the ground's distances from the camera, not from the card's foot)
    k = (ground_ahead(camera, np.array([lowest + lift]))[0] - here) / (ground_ahead(camera, np.array([foot]))[0] - here)
    return ground_rows(camera, here + k * (ground_ahead(camera, feet) - here)) - feet


def _band_lifts(
    reading: ContactReading,
    framing: Framing,
    camera: tuple[float, float] | None,
    feet: list[int],
    lift: float,
    relief: float = 1.0,
) -> list[int]:
    """:func:`rigid_lifts` of a cutout's bands, whose feet are rows of its alpha, lifted ``lift`` of its rows; its
    surfaces keep ``relief`` of their read distance from the cards (:class:`CardTracer`)."""
    if lift <= 0:
        return [0] * len(feet)
    alpha, s, y0 = reading.alpha, framing.scale, framing.bbox[1]

    def on_frame(rows: np.ndarray | list[int] | float) -> np.ndarray:  # rows of alpha -> frame rows
        return (np.asarray(rows, np.float64) + y0) * s + framing.offset_y

    frame, base = on_frame(feet), max(feet)
    row, col = lowest_pixel(alpha)
    # the lowest pixel's foot as it stood: as the surface model read it (never above the pixel; drawn towards the
    # lowest card with the rest of the relief), else the lowest card's
    read = base if reading.feet is None else float(reading.feet[row, col])
    if relief < 1.0:
        read = base + (read - base) * relief
    foot = on_frame(max(read, row + 0.5))
    top = on_frame(np.flatnonzero((alpha > ROWS_ALPHA).any(axis=1))[0])
    horizon, focal = camera if camera is not None else (None, None)
    cam = camera_for_span(framing.n, float(top), float(on_frame(base)), horizon, focal)[0]
    moved = rigid_lifts(cam, frame, float(on_frame(row + 0.5)), float(foot), lift * s) / s
    return [max(0, int(round(m))) for m in moved]


def coverage_level(peak: float) -> float:
    """The coverage a cutout's lowest pixel (:func:`lowest_pixel`) has at least, ``peak`` its highest: 0.5, or half
    the peak where the cutout is nowhere so opaque."""
    return min(0.5, 0.5 * peak)


def lowest_pixel(alpha: np.ndarray) -> tuple[int, int]:
    """The pixel (row, col) of ``alpha`` a lift is counted from (conventions, "Lift and thickness"): its lowest row
    with coverage >= 0.5, at that row's coverage-weighted mean column, or the row's nearest pixel of coverage
    >= 0.5 where the mean falls on less (a cutout nowhere so opaque: half its highest coverage in place of 0.5)."""
    peak = float(alpha.max())
    if peak <= 0:
        raise ValueError("the cutout is empty")
    covered = alpha >= coverage_level(peak)
    row = int(np.flatnonzero(covered.any(axis=1))[-1])
    weights = alpha[row].astype(np.float64)
    col = int(np.sum(weights * np.arange(len(weights))) / weights.sum() + 0.5)
    if not covered[row, col]:
        cols = np.flatnonzero(covered[row])
        col = int(cols[np.argmin(np.abs(cols - col))])
    return row, col


def _enlarged(small: np.ndarray, k: int, shape: tuple[int, int]) -> np.ndarray:
    """``small``, worked out on a copy reduced ``k`` times, enlarged bilinearly (float32) and cut to ``shape``."""
    small = np.ascontiguousarray(small, np.float32)
    if k > 1:
        size = (small.shape[1] * k, small.shape[0] * k)
        small = np.asarray(Image.fromarray(small, "F").resize(size, Image.Resampling.BILINEAR))
    return small[: shape[0], : shape[1]]


def foot_rows(shape: tuple[int, int], framing: Framing, heights: np.ndarray) -> np.ndarray:
    """(h, w) = ``shape``: the row (continuous) of the cutout's crop at ``framing.bbox`` of each pixel's foot, from
    the pixel heights ``heights`` (N, N) over the frame (frame rows: how far below each frame pixel its foot
    lies). Sampled on a copy reduced to about ``DEPTH_SIZE`` pixels and enlarged."""
    h, w = shape
    k = max(1, math.ceil(max(h, w) / DEPTH_SIZE))
    x0, y0 = framing.bbox[:2]
    rows, cols = np.arange(0, h, k) + 0.5 * k, np.arange(0, w, k) + 0.5 * k  # reduced pixels' centres
    fx, fy = (cols + x0) * framing.scale + framing.offset_x, (rows + y0) * framing.scale + framing.offset_y
    grid = np.meshgrid(fy - 0.5, fx - 0.5, indexing="ij")
    small = ndimage.map_coordinates(np.asarray(heights, np.float32), grid, order=1, mode="nearest") / framing.scale
    return _enlarged(small, k, (h, w)) + (np.arange(h, dtype=np.float32) + 0.5)[:, None]


@dataclass(frozen=True)
class ContactReading:
    """What a cutout's tracer reads from it once, whatever the artist's lift and thickness: the cutout's alpha,
    its contact line's bands (:func:`contact_bands`: columns and foot row each), its depth (:func:`depth_map`)
    and the thickness that reads as, and, with the frame's pixel heights, each pixel's foot row
    (:func:`foot_rows`) and, where the surface model reads the depth, its far surface's."""

    alpha: np.ndarray
    bands: list[tuple[int, int, int]]
    depth: np.ndarray
    thickness_read: float
    feet: np.ndarray | None
    far_feet: np.ndarray | None = None
    # per band: its card's :attr:`CardTracer.surface_depths` standing on the ground, made on a first lift
    at_rest: dict[BandKey, SurfaceDepths] = field(default_factory=dict, compare=False)

    @classmethod
    def of(
        cls, alpha: np.ndarray, framing: Framing, camera: tuple[float, float] | None, heights: np.ndarray | None = None
    ) -> ContactReading:
        """The reading of ``alpha`` (the cutout's crop at ``framing.bbox``) with ``camera``; ``heights`` (C, N, N),
        optional: the frame's pixel heights of the visible surface, and (C = 2) of the far surface."""
        alpha = np.clip(np.asarray(alpha, np.float32), 0.0, 1.0)
        depth = depth_map(alpha)
        feet = [] if heights is None else [foot_rows(alpha.shape, framing, h) for h in heights]
        return cls(
            alpha,
            contact_bands(alpha, footprint_rise(alpha, framing, camera)),
            depth,
            read_thickness(alpha, depth),
            feet[0] if feet else None,
            feet[1] if len(feet) > 1 else None,
        )


class ContactTracer:
    """The cutout as cards standing on its contact line: one :class:`CardTracer` per band of
    :func:`contact_bands`, cross-faded where two meet, their shadows added; ``heights`` (C, N, N), optional: the
    frame's pixel heights (:func:`foot_rows`), which place each pixel's surface behind its card, and (C = 2) its
    far surface's, where its depth ends (else :func:`depth_map`'s round cross-section).

    The artist's geometry (conventions, "Lift and thickness"): ``lift`` (pixels of ``alpha``) puts the foot of
    the cutout's lowest pixel that many rows below it, the object floating as one body (:func:`rigid_lifts`: each
    card's foot and its pixels' feet lower, a card farther back by fewer rows; its cards stand nearer, on the
    ground beneath it); ``thickness``, where given, scales the depth each pixel
    reaches behind its surface so that the object's depth over its width is that (:func:`read_thickness` is the
    reading it replaces; the round cross-section scaled, in place of a far surface read), and, below the reading,
    draws its footprint and its surfaces' relief together in that share (at 0 one plane). :meth:`of_reading`
    makes the cards of a reading already made (a new lift or thickness: the cutout is not read again)."""

    def __init__(
        self,
        alpha: np.ndarray,
        framing: Framing,
        camera: tuple[float, float] | None,
        heights: np.ndarray | None = None,
        lift: float = 0.0,
        thickness: float | None = None,
    ) -> None:
        self._make_cards(ContactReading.of(alpha, framing, camera, heights), framing, camera, lift, thickness)

    @classmethod
    def of_reading(
        cls,
        reading: ContactReading,
        framing: Framing,
        camera: tuple[float, float] | None,
        lift: float = 0.0,
        thickness: float | None = None,
        kept: dict[BandKey, Kept] | None = None,
    ) -> ContactTracer:
        """The tracer of a cutout read before (:class:`ContactReading`), with the artist's geometry; ``kept``: the
        :attr:`kept` of a tracer of the same reading (another lift or thickness), which its cards take over."""
        tracer = cls.__new__(cls)
        tracer._make_cards(reading, framing, camera, lift, thickness, kept)
        return tracer

    def _make_cards(
        self,
        reading: ContactReading,
        framing: Framing,
        camera: tuple[float, float] | None,
        lift: float,
        thickness: float | None,
        kept: dict[BandKey, Kept] | None = None,
    ) -> None:
        alpha, bands = reading.alpha, reading.bands
        outline = reading.thickness_read
        relief = 1.0  # the share of its read depth the object keeps: less where the artist gives less
        if thickness is not None and thickness < outline:
            # a contact line rising at the sides stands them farther back; an object given less depth than its
            # outline reads has a shallower footprint: its bands' feet drawn to the lowest in that share, and its
            # surfaces' relief with them (a flat sign, thickness 0, is one plane; else a round bottom's cards cast
            # strips apart)
            lowest, relief = max(foot for *_, foot in bands), thickness / outline
            bands = [(c0, c1, lowest - round((lowest - foot) * relief)) for c0, c1, foot in bands]
        depth: np.ndarray | None = reading.depth
        kept = kept or {}
        x0, y0 = framing.bbox[:2]
        self.cards: list[CardTracer] = []
        self.kept: dict[BandKey, Kept] = {}  # per band: its card's (:attr:`CardTracer.kept`)
        width = alpha.shape[1]
        self.thickness_read = reading.thickness_read  # the outline's; below, the far surface's where one is read
        far_feet = reading.far_feet
        if thickness is not None:  # the artist's replaces the reading: the round cross-section scaled
            depth = depth * np.float32(thickness / outline) if outline > 0 else depth * 0
        elif far_feet is not None:  # each pixel as deep as its far surface
            depth = None
        lifts = _band_lifts(reading, framing, camera, [foot for *_, foot in bands], lift, relief)
        layout = tuple(bands)
        columns = tuple((c0, c1) for c0, c1, _ in bands)  # what a card's alpha depends on (its foot: not)
        for i, ((c0, c1, foot), rows) in enumerate(zip(bands, lifts, strict=True)):
            weight = np.zeros(width, np.float32)
            weight[c0:c1] = 1.0
            if i > 0:
                r = max(1, int(RAMP * min(c1 - c0, bands[i - 1][1] - bands[i - 1][0])))
                ramp = (np.arange(-r, r) + 0.5) / (2 * r)
                weight[c0 - r : c0 + r] = ramp
            if i + 1 < len(bands):
                n0, n1 = bands[i + 1][:2]
                r = max(1, int(RAMP * min(c1 - c0, n1 - n0)))
                weight[c1 - r : c1 + r] = 1.0 - (np.arange(-r, r) + 0.5) / (2 * r)
            used = np.flatnonzero(weight > 0)
            a, b = int(used[0]), int(used[-1]) + 1
            part = alpha[:, a:b] if len(bands) == 1 else alpha[:, a:b] * weight[a:b]  # (a card copies its alpha)
            key = (layout, i)  # its surfaces at rest depend on its foot; what it keeps, on its columns

            card_at = partial(
                _band_card,
                part,
                framing,
                camera,
                (x0 + a, y0),
                foot,
                None if depth is None else depth[:, a:b],
                None if reading.feet is None else reading.feet[:, a:b],
                None if far_feet is None else far_feet[:, a:b],
                thickness,
                kept.get((columns, i)),
                relief,
            )
            if rows > 0 and reading.feet is not None and key not in reading.at_rest:
                rest = card_at(0)  # the same band standing on the ground: its surfaces as read (once a reading)
                if not rest.empty:
                    reading.at_rest[key] = rest.surface_depths
            card = card_at(rows, reading.at_rest.get(key) if rows > 0 else None)
            if rows == 0 and not card.empty:
                reading.at_rest.setdefault(key, card.surface_depths)
            if not card.empty:
                self.cards.append(card)
                self.kept[columns, i] = card.kept
        self.empty = not self.cards
        if far_feet is not None and self.cards:  # the far surface read: its deepest segment over the width
            self.thickness_read = read_thickness(alpha, np.asarray(max(c.deepest_read for c in self.cards)))

    def shadow(
        self, u: float, v: float, angle: float, framing: Framing, clip: bool = True
    ) -> tuple[np.ndarray, int, int]:
        """As :meth:`CardTracer.shadow`, the cards' shadows added (clipped to 1)."""
        if len(self.cards) == 1:  # (a card's shadow lies in [0, 1])
            return self.cards[0].shadow(u, v, angle, framing, clip)
        return placed_sum([(1.0, *c.shadow(u, v, angle, framing, clip)) for c in self.cards])
