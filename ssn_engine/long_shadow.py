"""Long shadows beyond the network's frame: the frame's shadow continued by the geometric card's.

The network sees an N x N frame in which the object fills about half the height, so a low sun's shadow (three
or more object heights long) runs out of it. When the frame's shadow reaches the frame's border, the card
(:meth:`ssn_engine.methods.geometric.GeometricCard.extended_shadow`, the same proxy geometry a geometry-guided
network refines) is traced on a grid ``MARGIN`` frames wider on every side; the frame's shadow is kept inside
the frame (its faint edge haze removed) and cross-fades into the card's over the frame's outer ``EDGE_FADE``
band, and the extended shadow fades out over the outer band of the wider grid.
"""

from __future__ import annotations

import numpy as np
from PIL import Image

from .framing import EDGE_FADE, edge_fade, without_edge_haze

MARGIN = 1.0  # frames added on each side: from the frame's centre a shadow may reach 1.5 frames (3 object heights)
CELL = 4.0  # frame pixels per cell of the card's wider grid
VISIBLE = 0.02  # a shadow this dark at the frame's border is continued beyond it


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
    ramp = edge_fade(n)
    inner = without_edge_haze(shadow)
    out[pad : pad + n, pad : pad + n] = ramp * inner + (1.0 - ramp) * out[pad : pad + n, pad : pad + n]
    return out.astype(np.float32), -float(pad)
