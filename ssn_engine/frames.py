"""Resampling N x N frames (masks, AO maps, shadows) between the engine's N and a network's R."""

from __future__ import annotations

import hashlib

import numpy as np
from PIL import Image
from scipy import ndimage


def frame_key(frame: np.ndarray, extra: bytes = b"") -> bytes:
    """A digest of a frame's float32 values (and ``extra``): the key of caches of work done per mask. SHA-1 (not
    against an adversary, only to tell masks apart) runs in hardware: 0.14 ms for a 256 x 256 frame against
    BLAKE2b's 0.28, once on every light change (the geometric card's lookup; the camera a model reads is
    resolved once per cutout and camera by the session)."""
    digest = hashlib.sha1(np.ascontiguousarray(frame, np.float32).data)
    digest.update(extra)
    return digest.digest()


def resample_frames(frames: np.ndarray, size: int) -> np.ndarray:
    """(n, H, H) -> (n, size, size) float32 with PIL's bilinear filter (antialiased when shrinking): how the ONNX
    method feeds its graphs and reads them back, and how training prepares the same inputs."""
    frames = np.asarray(frames, np.float32)
    if frames.shape[-1] == size:
        return np.ascontiguousarray(frames)
    return np.stack(
        [np.asarray(Image.fromarray(f, "F").resize((size, size), Image.Resampling.BILINEAR)) for f in frames]
    )


def nearest_fill(values: np.ndarray, known: np.ndarray) -> np.ndarray:
    """``values`` (..., h, w) with each pixel where ``known`` (bool, (h, w)) is False given its nearest known
    pixel's value, in every leading slice alike (as it is where every pixel or none is known)."""
    if known.all() or not known.any():
        return values
    _, (iy, ix) = ndimage.distance_transform_edt(~known, return_indices=True)  # type: ignore[misc]
    return values[..., iy, ix]
