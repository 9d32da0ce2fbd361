"""Row-span packing of quantised occlusion bases: compact, memory-mappable, exact.

Per texel t and frame row i only the columns [c0, c1) between the first and
the last non-zero value are kept; ``spans`` (T, N, 2) uint16 holds (c0, c1)
(0, 0 for an empty row) and ``data`` the kept values in (t, i, j) C order.
"""

from __future__ import annotations

import numpy as np


def quantise_counts(counts: np.ndarray, samples: int) -> np.ndarray:
    """Hit counts out of ``samples`` to uint8 occ * 255, rounded half up."""
    lut = np.floor(np.arange(samples + 1) * 255.0 / samples + 0.5).astype(np.uint8)
    return lut[counts]


def pack(occ: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """(T, N, N) uint8 -> spans (T, N, 2) uint16, data (K,) uint8 (numba when available)."""
    try:  # numba is optional: the numpy packer gives the same spans, slower
        from numba import njit
    except ImportError:
        return pack_numpy(occ)
    global _pack_compiled
    if _pack_compiled is None:
        _pack_compiled = njit(cache=True)(_pack_loops)
    spans, data, k = _pack_compiled(np.ascontiguousarray(occ))
    return spans, data[:k].copy()


_pack_compiled = None


def _pack_loops(occ):
    t_count, n, m = occ.shape
    spans = np.zeros((t_count, n, 2), np.uint16)
    data = np.empty(occ.size, np.uint8)
    k = 0
    for t in range(t_count):
        for i in range(n):
            lo = 0
            while lo < m and occ[t, i, lo] == 0:
                lo += 1
            if lo == m:
                continue
            hi = m
            while occ[t, i, hi - 1] == 0:
                hi -= 1
            spans[t, i, 0] = lo
            spans[t, i, 1] = hi
            for j in range(lo, hi):
                data[k] = occ[t, i, j]
                k += 1
    return spans, data, k


def pack_numpy(occ: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Pure-numpy :func:`pack` (same output)."""
    t, n, _ = occ.shape
    nz = occ != 0
    row_any = nz.any(axis=2)
    c0 = np.where(row_any, nz.argmax(axis=2), 0)
    c1 = np.where(row_any, n - nz[:, :, ::-1].argmax(axis=2), 0)
    spans = np.stack([c0, c1], axis=-1).astype(np.uint16)
    return spans, occ[_inside(spans, n)]


def unpack(spans: np.ndarray, data: np.ndarray, n: int) -> np.ndarray:
    """Inverse of :func:`pack`: (T, N, N) uint8."""
    out = np.zeros((spans.shape[0], spans.shape[1], n), np.uint8)
    out[_inside(spans, n)] = data
    return out


def _inside(spans: np.ndarray, n: int) -> np.ndarray:
    j = np.arange(n, dtype=np.uint16)
    return (j >= spans[..., :1]) & (j < spans[..., 1:])
