"""The interface every shadow method implements."""

from __future__ import annotations

from typing import Protocol

import numpy as np


class ShadowMethod(Protocol):
    """Mask -> AO map, then (mask, AO, ELM) -> shadow, on N x N frames.

    ``masks`` and ``ao`` have shape (n, N, N), ``elms`` (n, 16, 32), all
    float32; results are float32 in [0, 1]. AO maps follow the conventions
    (A^(1/3), 1 fully exposed). ``render`` is the interactive path: it must
    not redo the AO work.
    """

    name: str
    resolution: int

    def predict_ao(self, masks: np.ndarray) -> np.ndarray: ...

    def render(self, masks: np.ndarray, ao: np.ndarray, elms: np.ndarray) -> np.ndarray: ...


def check_batch(masks: np.ndarray, elms: np.ndarray | None, n: int, ao: np.ndarray | None = None) -> None:
    """Raise ValueError with the offending argument's name when shapes are off."""
    if masks.ndim != 3 or masks.shape[1:] != (n, n):
        raise ValueError(f"masks: expected shape (n, {n}, {n}), got {masks.shape}")
    if elms is not None and (elms.ndim != 3 or elms.shape[1:] != (16, 32) or len(elms) != len(masks)):
        raise ValueError(f"elms: expected shape ({len(masks)}, 16, 32), got {elms.shape}")
    if ao is not None and ao.shape != masks.shape:
        raise ValueError(f"ao: expected shape {masks.shape}, got {ao.shape}")
