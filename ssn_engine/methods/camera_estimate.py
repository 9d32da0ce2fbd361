"""The camera input estimated from the mask alone, for a blind call (no horizon row and focal length given).

The conventions' default camera (45 degree field of view, 15 degree pitch) is wrong for most views, and the
geometric card a geometry-guided SR refines is traced with that camera: its shadow then falls at the wrong
length and angle on the ground. The silhouette says much about the camera (the base of a round object is a
flat line seen level, an ellipse seen from above), so a small network reads it (``camera.onnx``, trained by
``training.camera_estimator``).

The network sees the mask in the engine's canonical framing (:func:`ssn_engine.framing.frame_alpha`: the
bounding box's longer side half the frame, its top on row round(0.03 N), centred), area-downsampled to
``INPUT`` pixels, and predicts the horizon row and the focal length in that frame divided by N; they are mapped
back to the caller's frame through the framing.
"""

from __future__ import annotations

from typing import TYPE_CHECKING

import numpy as np

from ..camera import focal_from_fov
from ..host_kit.camera_rules import DEFAULT_FOV
from ..framing import EmptyAlphaError, Framing, frame_alpha
from .base import clamp_cameras

if TYPE_CHECKING:
    import onnxruntime as ort

INPUT = 64  # the estimator's input side, pixels


def canonical_input(mask: np.ndarray) -> tuple[np.ndarray, Framing]:
    """A frame mask (N, N) reframed canonically and area-downsampled to (INPUT, INPUT), and the framing from
    the given frame to the canonical one."""
    n = mask.shape[0]
    canonical, framing = frame_alpha(mask, n)
    k = n // INPUT
    return canonical.reshape(INPUT, k, INPUT, k).mean(axis=(1, 3)), framing


def to_canonical(camera: tuple[float, float], framing: Framing) -> tuple[float, float]:
    """A camera input (horizon row, focal length) of the given frame in the canonical frame's pixels."""
    horizon, focal = camera
    return horizon * framing.scale + framing.offset_y, focal * framing.scale


def from_canonical(camera: tuple[float, float], framing: Framing) -> tuple[float, float]:
    """The inverse of :func:`to_canonical`."""
    horizon, focal = camera
    return (horizon - framing.offset_y) / framing.scale, focal / framing.scale


def estimate_cameras(session: ort.InferenceSession, masks: np.ndarray) -> np.ndarray:
    """Camera inputs (b, 2) for frame masks (b, N, N) from the estimator's onnxruntime ``session`` ("mask"
    [b, 1, INPUT, INPUT] -> "camera" [b, 2], divided by N). An empty mask casts no shadow: it gets the
    conventions' default focal length and a horizon through the frame's middle."""
    n = masks.shape[-1]
    out = np.empty((len(masks), 2))
    inputs, framings, rows = [], [], []
    for b, mask in enumerate(masks):
        try:
            x, framing = canonical_input(np.asarray(mask, np.float32))
        except EmptyAlphaError:
            out[b] = 0.5 * n, focal_from_fov(n, DEFAULT_FOV)
            continue
        inputs.append(x)
        framings.append(framing)
        rows.append(b)
    if rows:
        predicted = session.run(["camera"], {"mask": np.stack(inputs)[:, None].astype(np.float32)})[0] * n
        for b, (h, f), framing in zip(rows, predicted, framings, strict=True):
            out[b] = from_canonical((float(h), float(f)), framing)
    return clamp_cameras(out, n)  # within the camera input's bounds, whatever the network says
