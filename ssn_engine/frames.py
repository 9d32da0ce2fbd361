"""Resampling N x N frames (masks, AO maps, shadows) between the engine's N and a network's R."""

from __future__ import annotations

import hashlib

import numpy as np
from PIL import Image


def frame_key(frame: np.ndarray, extra: bytes = b"") -> bytes:
    """A digest of a frame's float32 values (and ``extra``): the key of caches of work done per mask."""
    data = np.ascontiguousarray(frame, np.float32).tobytes() + extra
    return hashlib.blake2b(data, digest_size=16).digest()


def resample_frames(frames: np.ndarray, size: int) -> np.ndarray:
    """(n, H, H) -> (n, size, size) float32 with PIL's bilinear filter (antialiased when shrinking): how the ONNX
    method feeds its graphs and reads them back, and how training prepares the same inputs."""
    frames = np.asarray(frames, np.float32)
    if frames.shape[-1] == size:
        return np.ascontiguousarray(frames)
    return np.stack(
        [np.asarray(Image.fromarray(f, "F").resize((size, size), Image.Resampling.BILINEAR)) for f in frames]
    )
