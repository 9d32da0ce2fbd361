"""The camera input read from the mask for blind calls (ssn_engine.methods.camera_estimate)."""

from __future__ import annotations

import numpy as np
import pytest
from engine_helpers import drawn_alpha

from ssn_engine.framing import alpha_bbox, frame_alpha
from ssn_engine.methods.camera_estimate import INPUT, canonical_input, from_canonical, to_canonical


def _view_frame() -> np.ndarray:
    """A frame as the dataset frames a view: the object smaller than the engine's half frame, off centre."""
    frame = np.zeros((256, 256), np.float32)
    frame[8:98, 40:110] = drawn_alpha(70, 90) / 255.0
    return frame


def test_the_estimator_sees_every_frame_in_the_canonical_framing():
    """However the caller framed the object, the estimator's input is the engine's canonical framing."""
    x, framing = canonical_input(_view_frame())
    canonical, _ = frame_alpha(drawn_alpha(70, 90), 256)
    assert x.shape == (INPUT, INPUT)
    expected = canonical.reshape(INPUT, 4, INPUT, 4).mean(axis=(1, 3))
    np.testing.assert_allclose(x, expected, atol=0.02)
    x0, y0, x1, y1 = alpha_bbox(_view_frame())
    assert framing.scale == pytest.approx(128 / max(x1 - x0, y1 - y0))  # the longer side becomes half the frame


def test_camera_inputs_map_to_the_canonical_frame_and_back():
    _, framing = canonical_input(_view_frame())
    camera = (-37.5, 301.0)
    horizon, focal = to_canonical(camera, framing)
    assert focal == pytest.approx(301.0 * framing.scale)
    assert horizon == pytest.approx(framing.to_frame(0.0, -37.5)[1])
    assert from_canonical((horizon, focal), framing) == pytest.approx(camera)
