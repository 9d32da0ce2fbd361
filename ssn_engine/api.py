"""The stable entry point for benchmarks: :func:`predict_frames` (see conventions.md)."""

from __future__ import annotations

import functools

import numpy as np

from .framing import ALPHA_THRESHOLD
from .host_kit.sky_map import check_elm_shape
from .methods import LoadedMethod, load_method
from .methods.base import check_cameras

BATCH = 16


@functools.lru_cache(maxsize=1)
def default_method() -> LoadedMethod:
    """The default method, loaded once per process."""
    return load_method("auto")


def _frames(name: str, array: np.ndarray, n: int | None = None) -> np.ndarray:
    a = np.asarray(array)
    if a.ndim != 3 or (n is not None and a.shape[1:] != (n, n)) or a.shape[1] != a.shape[2]:
        raise ValueError(f"{name}: expected shape (n, N, N), got {a.shape}")
    if not np.all(np.isfinite(a)):
        raise ValueError(f"{name}: contains NaN or infinite values")
    return np.ascontiguousarray(a, np.float32)


def predict_frames(
    masks: np.ndarray, elms: np.ndarray, ao: np.ndarray | None = None, cameras: np.ndarray | None = None
) -> np.ndarray:
    """Shadow maps s (n, N, N), float32 in [0, 1], from masks (n, N, N) and ELMs (n, 16, 32).

    Optional ``ao`` (n, N, N) replaces the predicted AO maps (e.g. ground
    truth or user-edited). Optional ``cameras`` (n, 2) gives each frame's
    horizon row and focal length in frame pixels (conventions, "Camera
    input"); without it the shipped model reads each frame's camera from its
    mask (its camera estimator), and a model without one or the geometric
    card assume the conventions' default camera (45 degree field of view,
    15 degree pitch). Uses the default shipped model,
    or the geometric card method while no trained model is installed.

    No visible shadow is exactly zero: a frame whose mask has no pixel above
    the framing's alpha threshold (nothing casts) or whose ELM is all zero
    (nothing lights) gets s = 0, as the CLI and the worker report "no
    visible shadow" for an empty cutout or a light map without light.
    """
    method = default_method().method
    masks = _frames("masks", masks, method.resolution)
    elms = np.asarray(elms)
    check_elm_shape(elms.shape, len(masks))
    if not np.all(np.isfinite(elms)) or elms.min(initial=0.0) < 0:
        raise ValueError("elms: light values must be finite and non-negative")
    elms = elms.astype(np.float32)
    if ao is not None:
        ao = _frames("ao", ao, method.resolution)
        if ao.shape != masks.shape:
            raise ValueError(f"ao: expected shape {masks.shape}, got {ao.shape}")
    if cameras is not None:
        cameras = np.asarray(cameras, np.float64)
        check_cameras(cameras, len(masks), method.resolution)
    out = np.empty(masks.shape, np.float32)
    for i in range(0, len(masks), BATCH):
        m = np.clip(masks[i : i + BATCH], 0.0, 1.0)
        cam = None if cameras is None else cameras[i : i + BATCH]
        a = method.predict_ao(m, cam) if ao is None else np.clip(ao[i : i + BATCH], 0.0, 1.0)
        out[i : i + BATCH] = method.render(m, a, elms[i : i + BATCH], cam)
    out[(masks.max(axis=(1, 2)) <= ALPHA_THRESHOLD) | (elms.max(axis=(1, 2)) <= 0)] = 0.0
    return np.clip(out, 0.0, 1.0)
