"""Shadow layers and composites.

The shadow layer holds the shadow colour in RGB and ``opacity * s`` as
straight alpha. In Multiply blend mode it gives exactly the conventions'
composite ``background * (1 - opacity * s * (1 - colour))``, which for a
black shadow is ``background * (1 - opacity * s)``.
"""

from __future__ import annotations

from collections.abc import Sequence

import numpy as np

from .framing import CanvasShadow
from .stripes import for_each_stripe

LAYER_DTYPES = ("uint8", "uint16", "float16", "float32")
_INT_MAX = {"uint8": 255, "uint16": 65535}


def _colour(color: Sequence[float]) -> np.ndarray:
    c = np.asarray(color, np.float32)
    if c.shape != (3,) or not np.all(np.isfinite(c)) or c.min() < 0 or c.max() > 1:
        raise ValueError(f"color: expected three numbers in [0, 1], got {list(color)!r}")
    return c


def _opacity(opacity: float) -> float:
    if not np.isfinite(opacity) or not 0.0 <= opacity <= 1.0:
        raise ValueError(f"opacity: expected a number in [0, 1], got {opacity!r}")
    return float(opacity)


def to_unit_float(image: np.ndarray) -> np.ndarray:
    """uint8/uint16/float image to float32 in [0, 1]."""
    if image.dtype.kind == "u":
        return image.astype(np.float32) / np.iinfo(image.dtype).max
    return np.clip(np.nan_to_num(image.astype(np.float32)), 0.0, 1.0)


def from_unit_float(image: np.ndarray, dtype: str | np.dtype) -> np.ndarray:
    """Float image in [0, 1] to the given dtype (rounding for integers)."""
    name = np.dtype(dtype).name
    if name in _INT_MAX:
        return np.rint(np.clip(image, 0.0, 1.0) * _INT_MAX[name]).astype(name)
    if name in ("float16", "float32", "float64"):
        return image.astype(name)
    raise ValueError(f"dtype: expected one of {LAYER_DTYPES}, got {name!r}")


def shadow_layer(
    shadow: np.ndarray | CanvasShadow,
    color: Sequence[float] = (0.0, 0.0, 0.0),
    opacity: float = 1.0,
    dtype: str = "uint8",
    channels: str = "rgba",
    out: np.ndarray | None = None,
) -> np.ndarray:
    """The shadow (h, w) as an RGBA or BGRA layer (h, w, 4) of the given dtype, made in ``out`` when given (an
    (h, w, 4) array of that dtype, for example a view into a larger layer)."""
    if channels not in ("rgba", "bgra"):
        raise ValueError(f"channels: expected 'rgba' or 'bgra', got {channels!r}")
    if dtype not in LAYER_DTYPES:
        raise ValueError(f"dtype: expected one of {LAYER_DTYPES}, got {dtype!r}")
    c = _colour(color)
    if channels == "bgra":
        c = c[::-1]
    if not isinstance(shadow, CanvasShadow):
        shadow = CanvasShadow(np.asarray(shadow), 0, 0)
    if out is None:
        out = np.empty(shadow.shape + (4,), dtype)
    elif out.shape != shadow.shape + (4,) or out.dtype != dtype:
        raise ValueError(f"out: expected {dtype} {shadow.shape + (4,)}, got {out.dtype} {out.shape}")
    colour_bytes = from_unit_float(c, dtype)
    top = _INT_MAX.get(dtype)
    scale = _opacity(opacity) * (top or 1.0)

    # In stripes (this runs on every light change, over the whole visible shadow): the stripe's alpha is made
    # scaled, and for integers offset by a half so that the cast rounds it.
    def fill(rows: slice) -> None:
        alpha = shadow.rows(rows, scale, 0.5 if top else 0.0)
        a = alpha.astype(dtype) if top else np.minimum(alpha, np.float32(scale), out=alpha).astype(dtype, copy=False)
        part = out[rows]
        if np.little_endian:
            _fill_words(part, a, colour_bytes)
        else:
            part[..., :3] = colour_bytes
            part[..., 3] = a

    for_each_stripe(fill, 0, shadow.shape[0], shadow.shape[1])
    return out


def _fill_words(part: np.ndarray, alpha: np.ndarray, colour: np.ndarray) -> None:
    """Fill pixels (h, w, 4) with ``colour`` (3,) and ``alpha`` (h, w), all of one dtype, in whole machine words
    (little-endian): one word per pixel for 8- and 16-bit channels, two for 32-bit ones, instead of four strided
    channel writes."""
    k = part.dtype.itemsize
    bits = alpha.view(f"u{k}")
    r, g, b = (int(v) for v in colour.view(f"u{k}"))
    if k == 4:  # (R, G) then (B, A) as two 64-bit words
        words = part.view(np.uint64)
        words[..., 0] = r | g << 32
        np.left_shift(bits, 32, out=words[..., 1], dtype=np.uint64)
        if b:
            words[..., 1] |= np.uint64(b)
        return
    word = np.dtype(f"u{4 * k}")
    words = part.view(word)[..., 0]
    np.left_shift(bits, 24 * k, out=words, dtype=word)
    if r or g or b:  # a black shadow (the default) is its alpha alone
        words |= word.type(r | g << 8 * k | b << 16 * k)


def composite_shadow(
    background: np.ndarray, shadow: np.ndarray, color: Sequence[float] = (0.0, 0.0, 0.0), opacity: float = 1.0
) -> np.ndarray:
    """Multiply a full-size shadow (H, W) into a background (H, W, 3|4); same dtype out."""
    if background.shape[:2] != shadow.shape:
        raise ValueError(f"background {background.shape[:2]} and shadow {shadow.shape} differ in size")
    bg = to_unit_float(background)
    factor = 1.0 - _opacity(opacity) * np.clip(shadow, 0, 1)[..., None] * (1.0 - _colour(color))
    out = bg.copy()
    out[..., :3] = bg[..., :3] * factor
    return from_unit_float(out, background.dtype)


def over(background: np.ndarray, cutout: np.ndarray) -> np.ndarray:
    """Alpha-composite an RGBA cutout (H, W, 4) over a background (H, W, 3|4); background dtype out."""
    if background.shape[:2] != cutout.shape[:2] or cutout.shape[2] != 4:
        raise ValueError("cutout must be RGBA and the same size as the background")
    bg, fg = to_unit_float(background), to_unit_float(cutout)
    a = fg[..., 3:4]
    out = bg.copy()
    out[..., :3] = fg[..., :3] * a + bg[..., :3] * (1.0 - a)
    if out.shape[2] == 4:
        out[..., 3:4] = a + bg[..., 3:4] * (1.0 - a)
    return from_unit_float(out, background.dtype)


def layer_image(
    shadow: CanvasShadow, width: int, height: int, color: Sequence[float] = (0.0, 0.0, 0.0), opacity: float = 1.0
) -> np.ndarray:
    """The canvas-sized uint8 RGBA shadow layer (:func:`shadow_layer` of the shadow pasted into an empty canvas),
    built without a canvas-sized float array."""
    out = np.empty((height, width, 4), np.uint8)
    out[..., :3] = from_unit_float(_colour(color), "uint8")
    out[..., 3] = 0
    if not shadow.is_empty:
        h, w = shadow.shape
        shadow_layer(shadow, color, opacity, out=out[shadow.y : shadow.y + h, shadow.x : shadow.x + w])
    return out


def composite_image(
    background: np.ndarray,
    cutout: np.ndarray,
    shadow: CanvasShadow,
    color: Sequence[float] = (0.0, 0.0, 0.0),
    opacity: float = 1.0,
) -> np.ndarray:
    """The shadow multiplied into ``background`` (H, W, 3|4) and the RGBA ``cutout`` (H, W, 4) over it: only the
    shadow's and the cutout's boxes are blended, in stripes. A writable ``background`` is written in place."""
    if background.shape[:2] != cutout.shape[:2] or cutout.shape[2] != 4:
        raise ValueError("cutout must be RGBA and the same size as the background")
    background = np.require(background, requirements="W")
    if not shadow.is_empty:
        h, w = shadow.shape
        cols = slice(shadow.x, shadow.x + w)

        def multiply(rows: slice) -> None:
            part = shadow.rows(slice(rows.start - shadow.y, rows.stop - shadow.y))
            background[rows, cols] = composite_shadow(background[rows, cols], part, color, opacity)

        for_each_stripe(multiply, shadow.y, shadow.y + h, w)
    visible = cutout[..., 3] > 0
    ys, xs = np.flatnonzero(visible.any(axis=1)), np.flatnonzero(visible.any(axis=0))
    del visible
    if ys.size:
        cols = slice(int(xs[0]), int(xs[-1]) + 1)

        def cover(rows: slice) -> None:
            background[rows, cols] = over(background[rows, cols], cutout[rows, cols])

        for_each_stripe(cover, int(ys[0]), int(ys[-1]) + 1, cols.stop - cols.start)
    return background


HORIZON_DASH = 6  # pixels on, pixels off
HORIZON_RGB = (255, 140, 0)
READ_HORIZON_DOT = 2  # the horizon the model read: a dotted line, one pixel in this many
READ_HORIZON_RGB = (40, 170, 255)


def preview_image(
    background: np.ndarray,
    shadow: CanvasShadow,
    cover: np.ndarray | None = None,
    color: Sequence[float] = (0.0, 0.0, 0.0),
    opacity: float = 1.0,
    horizon: float | None = None,
    read: bool = False,
) -> np.ndarray:
    """A dialog's preview: the shadow multiplied onto a small uint8 RGB(A) ``background`` (h, w, 3|4) as a
    Multiply layer would, hidden where the cutout above it covers the image (``cover``: its alpha (h, w), any
    dtype), with the ``horizon`` row as a dashed orange line, or, ``read``: a dotted blue one (the horizon the
    model read from the cutout's outline, not one the artist set). Returns packed RGB (h, w, 3) uint8."""
    h, w = background.shape[:2]
    rgb = background[..., :3].astype(np.float32)
    if not shadow.is_empty:
        sh, sw = shadow.shape
        x0, y0, x1, y1 = max(shadow.x, 0), max(shadow.y, 0), min(shadow.x + sw, w), min(shadow.y + sh, h)
        if x0 < x1 and y0 < y1:
            rows = shadow.rows(slice(y0 - shadow.y, y1 - shadow.y), _opacity(opacity))
            s = rows[:, x0 - shadow.x : x1 - shadow.x]
            if cover is not None:
                s = s * (1.0 - to_unit_float(cover[y0:y1, x0:x1]))
            rgb[y0:y1, x0:x1] *= 1.0 - s[..., None] * (1.0 - _colour(color))
    out = np.rint(np.clip(rgb, 0, 255)).astype(np.uint8)
    if horizon is not None and 0 <= np.floor(horizon) < h:
        x = np.arange(w)
        drawn = x % READ_HORIZON_DOT == 0 if read else (x // HORIZON_DASH) % 2 == 0
        out[int(np.floor(horizon)), drawn] = READ_HORIZON_RGB if read else HORIZON_RGB
    return out
