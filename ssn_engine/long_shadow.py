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


def extend(shadow: np.ndarray, wide: np.ndarray, margin: float = MARGIN) -> tuple[np.ndarray, float]:
    """Join a frame shadow (N, N) and the card's shadow on the wider grid (M, M) covering frame coordinates
    [-margin N, (1 + margin) N): returns the joined shadow at frame resolution and its origin, the frame
    coordinate of its top-left corner (the same on both axes)."""
    n = shadow.shape[0]
    pad = int(round(margin * n))
    size = n + 2 * pad
    out = np.asarray(Image.fromarray(wide.astype(np.float32), "F").resize((size, size), Image.Resampling.BILINEAR))
    out = np.clip(out, 0.0, 1.0) * edge_fade(size)
    weight = frame_weight(n)
    inside = out[pad : pad + n, pad : pad + n]
    inside += weight * (without_edge_haze(shadow) - inside)
    return out.astype(np.float32, copy=False), -float(pad)


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
