"""The interface every shadow method implements."""

from __future__ import annotations

from typing import Protocol

import numpy as np

from ..camera import focal_from_fov
from ..host_kit.camera_rules import FOV_RANGE
from ..host_kit.sky_map import check_elm_shape


class ShadowMethod(Protocol):
    """Mask -> AO map, then (mask, AO, ELM) -> shadow, on N x N frames.

    ``cameras`` (n, 2), optional: the camera input of the conventions (horizon
    row and focal length in frame pixels); None: the method's default camera.

    ``masks`` and ``ao`` have shape (n, N, N), ``elms`` (n, 16, 32), all
    float32; results are float32 in [0, 1]. AO maps follow the conventions
    (A^(1/3), 1 fully exposed). ``render`` is the interactive path: it must
    not redo the AO work, nor resolve the camera where it is given one (a
    session passes the camera it resolved once, a model's reading included).
    """

    name: str
    resolution: int

    def predict_ao(self, masks: np.ndarray, cameras: np.ndarray | None = None) -> np.ndarray: ...

    def render(
        self, masks: np.ndarray, ao: np.ndarray, elms: np.ndarray, cameras: np.ndarray | None = None
    ) -> np.ndarray: ...


def check_batch(
    masks: np.ndarray, elms: np.ndarray | None, n: int, ao: np.ndarray | None = None, cameras: np.ndarray | None = None
) -> None:
    """Raise ValueError with the offending argument's name when shapes or values are off."""
    if masks.ndim != 3 or masks.shape[1:] != (n, n):
        raise ValueError(f"masks: expected shape (n, {n}, {n}), got {masks.shape}")
    if elms is not None:
        check_elm_shape(elms.shape, len(masks))
    if ao is not None and ao.shape != masks.shape:
        raise ValueError(f"ao: expected shape {masks.shape}, got {ao.shape}")
    if cameras is not None:
        check_cameras(cameras, len(masks), n)


HORIZON_REACH = 100  # camera input: horizon rows within this many frames above or below the frame


def camera_limits(n: int) -> tuple[tuple[float, float], tuple[float, float]]:
    """The camera input's bounds for frames of ``n`` pixels: horizon rows within ``HORIZON_REACH`` frames of the
    frame, focal lengths of a field of view in :data:`~ssn_engine.host_kit.camera_rules.FOV_RANGE`; ((horizon lo,
    hi), (focal lo, hi))."""
    lo, hi = FOV_RANGE
    return (n / 2 - HORIZON_REACH * n, n / 2 + HORIZON_REACH * n), (focal_from_fov(n, hi), focal_from_fov(n, lo))


def clamp_cameras(cameras: np.ndarray, n: int) -> np.ndarray:
    """Camera inputs (b, 2) moved inside :func:`camera_limits`."""
    (h_lo, h_hi), (f_lo, f_hi) = camera_limits(n)
    return np.stack([np.clip(cameras[:, 0], h_lo, h_hi), np.clip(cameras[:, 1], f_lo, f_hi)], axis=1)


def check_cameras(cameras: np.ndarray, count: int, n: int) -> None:
    """Camera inputs for frames of ``n`` pixels: shape (count, 2), inside :func:`camera_limits`."""
    if cameras.shape != (count, 2):
        raise ValueError(f"cameras: expected shape ({count}, 2) (horizon row, focal length), got {cameras.shape}")
    (h_lo, h_hi), (lo, hi) = camera_limits(n)
    if (
        not np.all(np.isfinite(cameras))
        or np.any(cameras[:, 0] < h_lo)
        or np.any(cameras[:, 0] > h_hi)
        or np.any(cameras[:, 1] < lo)
        or np.any(cameras[:, 1] > hi)
    ):
        raise ValueError(
            f"cameras: horizon rows must lie within {HORIZON_REACH} frames of the frame and focal "
            f"lengths in [{lo:.1f}, {hi:.0f}] pixels (a field of view from {FOV_RANGE[0]:g} to {FOV_RANGE[1]:g} "
            "degrees)"
        )
