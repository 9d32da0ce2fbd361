"""Area-averaging frames from the dataset's N to the network's R (bilinear resampling: ssn_engine.frames)."""

from __future__ import annotations

import numpy as np


def area_downsample(stack: np.ndarray, size: int) -> np.ndarray:
    """Mean over f x f pixel blocks of (..., N, N) -> (..., size, size) float32; exact for linear quantities."""
    n = stack.shape[-1]
    if n == size:
        return np.asarray(stack, np.float32)
    f = n // size
    if f * size != n:
        raise ValueError(f"frame size {n} is not a multiple of {size}")
    stack = np.asarray(stack)
    if stack.dtype == np.uint8 and f * f <= 256:  # exact integer sums, 4x less memory traffic than float
        rows = stack[..., 0::f, :].astype(np.uint16)
        for k in range(1, f):
            rows += stack[..., k::f, :]
        total = rows[..., 0::f].copy()
        for k in range(1, f):
            total += rows[..., k::f]
        return (total / np.float32(f * f)).astype(np.float32)
    lead = stack.shape[:-2]
    blocks = stack.reshape(lead + (size, f, size, f))
    return blocks.astype(np.float32).mean(axis=(-3, -1))
