"""From a canvas-sized alpha to the network's N x N frame, and back.

The frame follows ``docs/conventions.md``: the object's top lies on
row round(0.03 N) and the object is centred horizontally. Its size in the
frame is fixed: the larger side of the alpha's bounding box becomes
``OBJECT_EXTENT * N`` pixels, the typical size of a training object seen
from the conventions' camera (an object with an AABB diagonal of 1, seen
from distance 2 with a 45 degree field of view, covers 0.35 to 0.6 of the
frame). The frame's ground below and beside the object holds the shadow.

Coordinates are continuous: pixel (i, j) covers [j, j + 1) x [i, i + 1), and
frame = canvas * scale + offset on both axes.
"""

from __future__ import annotations

import functools
import math
from dataclasses import dataclass

import numpy as np
from PIL import Image

from .camera import focal_from_fov, fov_from_focal, top_row
from .host_kit.camera_rules import DEFAULT_FOV, check_fov
from .stripes import for_each_stripe

OBJECT_EXTENT = 0.5
ALPHA_THRESHOLD = 0.01  # alpha at or below this is background for the bounding box
MIN_CUTOUT = 3  # pixels on the cutout's longer side; a smaller one casts no visible shadow
SHADOW_FLOOR = 0.5 / 255  # shadow below this is invisible in 8 bits: the layer is cropped to the rest
EDGE_FADE = 0.04  # share of the frame over which a shadow fades out at the frame's edges
HAZE, HAZE_BAND = 0.04, 0.12  # faint values removed near the frame's edges, and over what share of the frame
BODY_QUANTILE = 0.9  # a cutout's opacity is this quantile of its visible mask: its body's, not a stray pixel's
OPAQUE = 0.98  # an opacity at or above this is an opaque cutout's (its antialiased edge resampled)


class EmptyAlphaError(ValueError):
    """The alpha has no visible pixel, so there is nothing to cast a shadow."""


@dataclass(frozen=True)
class Framing:
    """How a canvas maps onto the frame: frame = canvas * scale + (offset_x, offset_y)."""

    n: int
    canvas_width: int
    canvas_height: int
    scale: float
    offset_x: float
    offset_y: float
    bbox: tuple[int, int, int, int]  # x0, y0, x1, y1 of the alpha on the canvas (x1, y1 exclusive)

    def to_frame(self, x: float, y: float) -> tuple[float, float]:
        """Canvas point to frame point."""
        return x * self.scale + self.offset_x, y * self.scale + self.offset_y

    def to_canvas(self, x: float, y: float) -> tuple[float, float]:
        """Frame point to canvas point."""
        return (x - self.offset_x) / self.scale, (y - self.offset_y) / self.scale

    def scaled(self, factor: float) -> Framing:
        """The same framing for the canvas resampled by ``factor`` (a preview of it): canvas sizes rounded."""
        x0, y0, x1, y1 = self.bbox
        return Framing(
            self.n,
            max(1, round(self.canvas_width * factor)),
            max(1, round(self.canvas_height * factor)),
            self.scale / factor,
            self.offset_x,
            self.offset_y,
            (math.floor(x0 * factor), math.floor(y0 * factor), math.ceil(x1 * factor), math.ceil(y1 * factor)),
        )

    def padded(self, margin: int) -> Framing:
        """The same framing on the canvas grown by ``margin`` pixels on every side (its origin moved to the
        grown canvas's corner): a layer clipped to it keeps what a host can show when the layer is moved a
        little."""
        x0, y0, x1, y1 = self.bbox
        return Framing(
            self.n,
            self.canvas_width + 2 * margin,
            self.canvas_height + 2 * margin,
            self.scale,
            self.offset_x - margin * self.scale,
            self.offset_y - margin * self.scale,
            (x0 + margin, y0 + margin, x1 + margin, y1 + margin),
        )

    def camera_input(self, horizon: float, fov: float = DEFAULT_FOV) -> tuple[float, float]:
        """The frame's camera input (horizon row h, focal length f; conventions "Camera input") for a canvas
        horizon row ``horizon`` (canvas pixels from the top edge; may lie outside the canvas) and the canvas's
        vertical field of view ``fov`` in degrees: h = k H + d, f = k F with F the canvas's focal length."""
        return horizon * self.scale + self.offset_y, focal_from_fov(self.canvas_height, check_fov(fov)) * self.scale

    def canvas_camera(self, horizon: float, focal: float) -> tuple[float, float]:
        """The inverse of :meth:`camera_input`: the canvas horizon row and vertical field of view (degrees) of a
        frame's camera input (horizon row h, focal length f)."""
        return (horizon - self.offset_y) / self.scale, fov_from_focal(self.canvas_height, focal / self.scale)


@dataclass(frozen=True)
class _Enlarged:
    """Canvas rows sampled bilinearly from a frame seen larger than itself: the frame rows needed, already
    interpolated across (``across`` (k, w)), the one above each canvas row's centre (``above`` (h,), into
    ``across``) and the share of the one below (``below_share`` (h, 1))."""

    across: np.ndarray
    above: np.ndarray
    below_share: np.ndarray

    def rows(self, rows: slice, scale: float, offset: float) -> np.ndarray:
        """Canvas rows ``rows`` (h', w), times ``scale`` plus ``offset``: the two frame rows around each canvas
        row mixed by its share (the scale and offset applied to the few frame rows, not the canvas rows)."""
        above = self.above[rows]
        first, last = int(above[0]), int(above[-1]) + 2
        span = np.clip(self.across[first:last], 0.0, 1.0) * np.float32(scale)
        step = np.diff(span, axis=0)
        span += np.float32(offset)
        out = np.take(step, above - first, axis=0)
        out *= self.below_share[rows]
        out += np.take(span, above - first, axis=0)
        return out


class CanvasShadow:
    """A shadow at canvas resolution: (h, w) values in [0, 1] placed at (x, y) on the canvas. It holds them as an
    array, or (a frame enlarged onto the canvas, from :func:`shadow_to_canvas`) as the frame rows they are
    sampled from, so that a layer is made a band of rows at a time (:meth:`rows`) without a canvas-sized float
    array; :attr:`values` makes them all."""

    @classmethod
    def nothing(cls) -> CanvasShadow:
        """No visible shadow (0 x 0 values)."""
        return cls(np.zeros((0, 0), np.float32), 0, 0)

    def __init__(self, values: np.ndarray | _Enlarged, x: int, y: int) -> None:
        self.x, self.y = x, y
        if isinstance(values, _Enlarged):
            self._source: np.ndarray | _Enlarged = values
            self.shape = (values.above.size, values.across.shape[1])
        else:
            self._source = self.values = values
            self.shape = values.shape

    @functools.cached_property
    def values(self) -> np.ndarray:
        """The (h, w) values (float32), made on first use."""
        out = np.empty(self.shape, np.float32)

        def fill(rows: slice) -> None:
            out[rows] = self.rows(rows)

        for_each_stripe(fill, 0, self.shape[0], self.shape[1])
        return out

    @property
    def is_empty(self) -> bool:
        return self.shape[0] * self.shape[1] == 0

    def rows(self, rows: slice, scale: float = 1.0, offset: float = 0.0) -> np.ndarray:
        """Rows ``rows`` (of the shadow, not the canvas) of the values clipped to [0, 1], times ``scale`` plus
        ``offset``: a new float32 array."""
        if isinstance(self._source, _Enlarged):
            return self._source.rows(rows, scale, offset)
        out = np.multiply(np.clip(self._source[rows], 0.0, 1.0), np.float32(scale), dtype=np.float32)
        out += np.float32(offset)
        return out

    def full_canvas(self, width: int, height: int) -> np.ndarray:
        """The shadow pasted into a zero canvas of the given size."""
        out = np.zeros((height, width), np.float32)
        h, w = self.shape
        out[self.y : self.y + h, self.x : self.x + w] = self.values
        return out


def union_box(boxes: list[tuple[int, int, int, int]]) -> tuple[int, int, int, int]:
    """The box (x0, y0, x1, y1) that holds boxes (x, y, width, height) (at least one)."""
    return (
        min(b[0] for b in boxes),
        min(b[1] for b in boxes),
        max(b[0] + b[2] for b in boxes),
        max(b[1] + b[3] for b in boxes),
    )


def placed_sum(
    parts: list[tuple[float, np.ndarray, int, int]], darker: tuple[CanvasShadow, float] | None = None
) -> tuple[np.ndarray, int, int]:
    """Placed values (share, values (h, w), x, y), each array's top-left pixel at (x, y), summed with their
    shares over the union of their boxes, and where ``darker`` (a shadow, times a scale) is darker, that:
    (values, x, y), clipped to [0, 1]; (0, 0) values when every part is empty."""
    boxes = [(x, y, v.shape[1], v.shape[0]) for _, v, x, y in parts if v.size]
    shade, scale = darker if darker is not None and not darker[0].is_empty else (None, 1.0)
    if shade is not None:
        boxes.append((shade.x, shade.y, shade.shape[1], shade.shape[0]))
    if not boxes:
        return np.zeros((0, 0), np.float32), 0, 0
    whole = [(v, x, y) for share, v, x, y in parts if v.size and share == 1.0]
    if len(boxes) == 1 and shade is None and whole:  # one part, whole: nothing to add up
        values, x, y = whole[0]
        return np.clip(values, 0.0, 1.0, dtype=np.float32), x, y
    x0, y0, x1, y1 = union_box(boxes)
    out = np.empty((y1 - y0, x1 - x0), np.float32)

    def fill(rows: slice) -> None:  # rows of ``out``, on the machine's cores
        band = out[rows]
        band.fill(0.0)
        for share, values, x, y in parts:
            a, b = max(rows.start, y - y0), min(rows.stop, y - y0 + values.shape[0])
            if values.size and b > a:
                window = band[a - rows.start : b - rows.start, x - x0 : x - x0 + values.shape[1]]
                part = values[a - (y - y0) : b - (y - y0)]
                window += part if share == 1.0 else np.float32(share) * part
        if shade is not None:
            dy = shade.y - y0
            a, b = max(rows.start, dy), min(rows.stop, dy + shade.shape[0])
            if b > a:
                window = band[a - rows.start : b - rows.start, shade.x - x0 : shade.x - x0 + shade.shape[1]]
                np.maximum(window, shade.rows(slice(a - dy, b - dy), scale), out=window)
        np.clip(band, 0.0, 1.0, out=band)

    for_each_stripe(fill, 0, y1 - y0, x1 - x0)
    return out, x0, y0


def as_unit_float(alpha: np.ndarray) -> np.ndarray:
    """An alpha of uint8, uint16 or float as float32 in [0, 1] (NaN as 0)."""
    if alpha.dtype == np.uint8:
        return alpha.astype(np.float32) / 255.0
    if alpha.dtype == np.uint16:
        return alpha.astype(np.float32) / 65535.0
    values = np.nan_to_num(alpha.astype(np.float32), nan=0.0)
    return np.clip(values, 0.0, 1.0)


def alpha_threshold(dtype: np.dtype) -> float:
    """``ALPHA_THRESHOLD`` in the units of an alpha of ``dtype``: at or below it a pixel is background."""
    if dtype == np.uint8:
        return ALPHA_THRESHOLD * 255
    if dtype == np.uint16:
        return ALPHA_THRESHOLD * 65535
    return ALPHA_THRESHOLD


def alpha_bbox(alpha: np.ndarray) -> tuple[int, int, int, int]:
    """Bounding box (x0, y0, x1, y1) of the visible alpha; EmptyAlphaError when there is none."""
    if alpha.ndim != 2 or alpha.size == 0:
        raise ValueError(f"alpha must be a non-empty 2D array, got shape {alpha.shape}")
    visible = alpha > alpha_threshold(alpha.dtype)
    rows = np.flatnonzero(visible.any(axis=1))
    if rows.size == 0:
        raise EmptyAlphaError("the selection or layer alpha is empty (fully transparent): nothing to cast a shadow")
    cols = np.flatnonzero(visible[rows[0] : rows[-1] + 1].any(axis=0))
    w, h = int(cols[-1] - cols[0]) + 1, int(rows[-1] - rows[0]) + 1
    if max(w, h) < MIN_CUTOUT:
        raise EmptyAlphaError(
            f"the cutout is only {w} x {h} pixels: too small to cast a visible shadow (it needs "
            f"{MIN_CUTOUT} pixels on its longer side)"
        )
    return int(cols[0]), int(rows[0]), int(cols[-1]) + 1, int(rows[-1]) + 1


def frame_alpha(alpha: np.ndarray, n: int = 256) -> tuple[np.ndarray, Framing]:
    """Frame a canvas alpha (H, W) of uint8, uint16 or float for the network.

    Returns the mask (n, n) float32 in [0, 1] and the :class:`Framing`. Only
    the bounding box is converted, so huge canvases stay cheap.
    """
    x0, y0, x1, y1 = alpha_bbox(alpha)
    bw, bh = x1 - x0, y1 - y0
    scale = OBJECT_EXTENT * n / max(bw, bh)
    col0 = int(round(0.5 * n - 0.5 * bw * scale))
    row0 = top_row(n)
    framing = Framing(n, alpha.shape[1], alpha.shape[0], scale, col0 - x0 * scale, row0 - y0 * scale, (x0, y0, x1, y1))
    fw, fh = min(math.ceil(bw * scale), n - col0), min(math.ceil(bh * scale), n - row0)
    pad = math.ceil(1.0 / scale) + 1  # zero margin: the box may reach past the bbox by a frame pixel
    crop = np.zeros((bh + 1 + pad, bw + 1 + pad), np.float32)
    crop[1 : bh + 1, 1 : bw + 1] = as_unit_float(alpha[y0:y1, x0:x1])
    box = (1.0, 1.0, 1.0 + fw / scale, 1.0 + fh / scale)
    resized = Image.fromarray(crop, "F").resize((fw, fh), Image.Resampling.BILINEAR, box=box)
    mask = np.zeros((n, n), np.float32)
    mask[row0 : row0 + fh, col0 : col0 + fw] = np.clip(np.asarray(resized), 0.0, 1.0)
    return mask, framing


def cutout_opacity(mask: np.ndarray) -> float:
    """How opaque a framed cutout's body is (in (0, 1]): the ``BODY_QUANTILE`` of its visible mask values, 1 where
    that reads opaque (``OPAQUE``). A half-transparent cutout (a layer's opacity times its alpha) casts the
    shadow of its opaque shape, this much as dark; its edges and a few denser pixels do not decide it."""
    visible = mask[mask > ALPHA_THRESHOLD]
    if visible.size == 0:
        return 0.0
    level = float(np.quantile(visible, BODY_QUANTILE))
    return 1.0 if level >= OPAQUE else level


@functools.lru_cache(maxsize=8)
def edge_fade(n: int, share: float = EDGE_FADE) -> np.ndarray:
    """(n, n) weights that fall linearly to 0 at the frame's four edges over ``share`` of the frame (read-only:
    cached, every light change uses it)."""
    ramp = np.clip((np.arange(n) + 0.5) / max(share * n, 1.0), 0.0, 1.0)
    across = np.minimum(ramp, ramp[::-1])
    out = np.minimum.outer(across, across).astype(np.float32)
    out.flags.writeable = False
    return out


def without_edge_haze(shadow: np.ndarray) -> np.ndarray:
    """A frame shadow (n, n) whose faint values are removed near the frame's edges: up to ``HAZE``, more and more
    over the outer ``HAZE_BAND`` (a network's faint haze would otherwise end in a visible rectangle there)."""
    return np.maximum(shadow - HAZE * (1.0 - edge_fade(shadow.shape[0], HAZE_BAND)), 0.0)


def fade_at_edges(shadow: np.ndarray) -> np.ndarray:
    """A frame shadow (n, n) without edge haze, faded to 0 over the frame's outer ``EDGE_FADE``."""
    return without_edge_haze(shadow) * edge_fade(shadow.shape[0])


def shadow_to_canvas(
    shadow: np.ndarray, framing: Framing, origin: tuple[float, float] | None = None, clip: bool = True
) -> CanvasShadow:
    """Resample a frame shadow to the canvas, cropped to its visible part.

    The result covers the canvas pixels whose shadow can be visible (the
    frame's shadow above ``SHADOW_FLOOR``), clipped to the canvas unless
    ``clip`` is False (then it may start at negative coordinates and reach
    past the canvas: for hosts whose layers can); it may reach well beyond
    the alpha's bounding box. A frame shadow (n, n) that
    runs out of the frame fades out (:func:`fade_at_edges`) instead of
    ending in a hard edge. With ``origin``, ``shadow`` is an array whose top-left
    corner lies at frame coordinates ``origin`` (x, y) and that fades out by
    itself (:func:`ssn_engine.long_shadow.extend`).
    """
    if origin is None:
        shadow, origin = fade_at_edges(shadow), (0.0, 0.0)
    ox, oy = origin
    visible = shadow > SHADOW_FLOOR
    rows, cols = np.flatnonzero(visible.any(axis=1)), np.flatnonzero(visible.any(axis=0))
    if rows.size == 0:
        return CanvasShadow.nothing()
    cx0, cy0 = framing.to_canvas(cols[0] + ox, rows[0] + oy)
    cx1, cy1 = framing.to_canvas(cols[-1] + 1 + ox, rows[-1] + 1 + oy)
    x0, y0, x1, y1 = math.floor(cx0), math.floor(cy0), math.ceil(cx1), math.ceil(cy1)
    if clip:
        x0, y0 = max(0, x0), max(0, y0)
        x1, y1 = min(framing.canvas_width, x1), min(framing.canvas_height, y1)
    if x1 <= x0 or y1 <= y0:
        return CanvasShadow.nothing()
    s = framing.scale
    pad = math.ceil(s) + 1  # zero margin so the samples never leave the padded frame
    padded = np.pad(np.asarray(shadow, np.float32), pad)
    left, top = x0 * s + framing.offset_x + pad - ox, y0 * s + framing.offset_y + pad - oy
    size = (x1 - x0, y1 - y0)
    if s < 1.0:
        return CanvasShadow(_enlarge(padded, (left, top), s, size), x0, y0)
    # Bilinear and antialiasing weights are non-negative and sum to 1: values stay in [0, 1].
    return CanvasShadow(_shrink(padded, (left, top), s, size), x0, y0)


def _shrink(frame: np.ndarray, corner: tuple[float, float], s: float, size: tuple[int, int]) -> np.ndarray:
    """The (height, width) canvas pixels whose top-left corner lies at frame point ``corner``, at ``s`` frame
    pixels per canvas pixel (s >= 1): PIL's separable resize (samples at canvas pixel centres, antialiased)."""
    (left, top), (width, height) = corner, size
    image = Image.fromarray(frame, "F")
    out = np.empty((height, width), np.float32)

    # In stripes of rows: the same samples, but without canvas-sized temporaries (PIL's own buffers are
    # reused), and on every core.
    def resample(rows: slice) -> None:
        box = (left, top + rows.start * s, left + width * s, top + rows.stop * s)
        out[rows] = np.asarray(image.resize((width, rows.stop - rows.start), Image.Resampling.BILINEAR, box=box))

    for_each_stripe(resample, 0, height, width)
    return out


def _enlarge(frame: np.ndarray, corner: tuple[float, float], s: float, size: tuple[int, int]) -> _Enlarged:
    """:func:`_shrink`'s samples for s < 1, made on demand (within float rounding) and several times faster: PIL
    interpolates along x only the few frame rows needed; down the canvas each canvas row mixes the two frame
    rows around its centre (PIL's vertical pass over a large canvas was most of a light change's time)."""
    (left, top), (width, height) = corner, size
    y = top + (np.arange(height) + 0.5) * s - 0.5  # the frame row at each canvas row's centre
    above = np.floor(y).astype(np.intp)
    first, last = int(above[0]), int(above[-1]) + 2
    band = Image.fromarray(frame[first:last], "F")
    box = (left, 0.0, left + width * s, float(last - first))
    across = np.asarray(band.resize((width, last - first), Image.Resampling.BILINEAR, box=box))
    return _Enlarged(across, above - first, (y - above).astype(np.float32)[:, None])
