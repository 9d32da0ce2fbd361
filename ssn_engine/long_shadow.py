"""Long shadows beyond the network's frame: the frame's shadow continued by the geometric card's.

The network sees an N x N frame in which the object fills about half the height, so a low sun's shadow (three
or more object heights long) runs out of it. When the frame's shadow reaches the frame's border, the card
(:meth:`ssn_engine.methods.geometric.GeometricCard.extended_shadow`, the same proxy geometry a geometry-guided
network refines) is traced on a grid ``MARGIN`` frames wider on every side; the frame's shadow is kept inside
the frame (its faint edge haze removed) and cross-fades into the card's along round contours (:func:`frame_weight`),
from ``JOIN_INNER`` of the way out to the frame's border, so that where the two disagree the network's pool fades
into the card's shadow gradually and without a straight seam; the extended shadow fades out over the outer band
of the wider grid.
"""

from __future__ import annotations

import functools
import math

import numpy as np
from PIL import Image

from .framing import EDGE_FADE, edge_fade, without_edge_haze

MARGIN = 1.0  # frames added on each side: from the frame's centre a shadow may reach 1.5 frames (3 object heights)
CELL = 4.0  # frame pixels per cell of the card's wider grid
VISIBLE = 0.02  # a shadow this dark at the frame's border is continued beyond it
JOIN_INNER = 0.55  # the cross-fade starts this far from the frame's centre (1: its border), along round contours


def reaches_border(shadow: np.ndarray) -> bool:
    """Whether a frame shadow (N, N) is visible (above ``VISIBLE``) in the frame's outer fade band, where it
    would otherwise be faded out."""
    band = max(1, int(np.ceil(EDGE_FADE * shadow.shape[0])))
    edges = (shadow[:band], shadow[-band:], shadow[:, :band], shadow[:, -band:])
    return max(float(e.max()) for e in edges) > VISIBLE


def extend(
    shadow: np.ndarray,
    wide: np.ndarray,
    margin: float = MARGIN,
    window: tuple[float, float, float, float] | None = None,
) -> tuple[np.ndarray, tuple[float, float]]:
    """Join a frame shadow (N, N) and the card's shadow on the wider grid (M, M) covering frame coordinates
    [-margin N, (1 + margin) N): returns the joined shadow at frame resolution and its origin, the frame
    coordinates (x, y) of its top-left corner. With ``window`` (x0, y0, x1, y1) in frame coordinates (a clipped
    canvas's), only the part that covers it is made: a canvas sees a fraction of a long shadow's reach."""
    n = shadow.shape[0]
    pad = int(round(margin * n))
    size = n + 2 * pad
    c0, r0, c1, r1 = 0, 0, size, size
    if window is not None:  # in pixels of the joined array, one more on each side for the canvas's bilinear samples
        c0, r0 = (max(0, min(size, math.floor(v + pad) - 1)) for v in window[:2])
        c1, r1 = (max(0, min(size, math.ceil(v + pad) + 1)) for v in window[2:])
        if c1 <= c0 or r1 <= r0:  # the window misses the joined shadow
            return np.zeros((0, 0), np.float32), (0.0, 0.0)
    cell = wide.shape[0] / size
    out = np.asarray(
        Image.fromarray(wide.astype(np.float32), "F").resize(
            (c1 - c0, r1 - r0), Image.Resampling.BILINEAR, box=(c0 * cell, r0 * cell, c1 * cell, r1 * cell)
        )
    )
    out = np.clip(out, 0.0, 1.0) * edge_fade(size)[r0:r1, c0:c1]
    # where the window covers the frame: frame rows [fr0, fr1) and columns [fc0, fc1)
    fr0, fr1, fc0, fc1 = max(r0 - pad, 0), min(r1 - pad, n), max(c0 - pad, 0), min(c1 - pad, n)
    if fr0 < fr1 and fc0 < fc1:
        inside = out[fr0 + pad - r0 : fr1 + pad - r0, fc0 + pad - c0 : fc1 + pad - c0]
        weight = frame_weight(n)[fr0:fr1, fc0:fc1]
        inside += weight * (without_edge_haze(shadow)[fr0:fr1, fc0:fc1] - inside)
    return out.astype(np.float32, copy=False), (float(c0 - pad), float(r0 - pad))


@functools.lru_cache(maxsize=4)
def frame_weight(n: int, inner: float = JOIN_INNER) -> np.ndarray:
    """(n, n) weights of the frame's shadow where it joins the card's: 1 within ``inner`` of the frame's centre
    (in half-frames), 0 from the frame's border outwards, a smoothstep of the distance in between (read-only)."""
    c = np.abs((np.arange(n) + 0.5) / n * 2.0 - 1.0)
    r = np.hypot(c[:, None], c[None, :])
    t = np.clip((1.0 - r) / (1.0 - inner), 0.0, 1.0)
    out = (t * t * (3.0 - 2.0 * t)).astype(np.float32)
    out.flags.writeable = False
    return out
