"""Fixtures for the engine tests."""

from __future__ import annotations

import numpy as np
import pytest
from engine_helpers import pawn

from ssn_engine.framing import frame_alpha


@pytest.fixture(scope="session")
def pawn_rgba() -> np.ndarray:
    """The bundled sample pawn cutout (900 x 1200 RGBA uint8); read-only."""
    return pawn()


@pytest.fixture(scope="session")
def pawn_frame(pawn_rgba) -> np.ndarray:
    """The pawn framed at N = 256 (float32 mask), read-only."""
    mask, _ = frame_alpha(np.ascontiguousarray(pawn_rgba[..., 3]), 256)
    mask.setflags(write=False)
    return mask


@pytest.fixture(scope="session")
def geometric():
    from ssn_engine.methods import GeometricCard

    return GeometricCard()


@pytest.fixture(autouse=True)
def _no_model_env(monkeypatch):
    """Tests run with the package's (empty) model folder unless they set their own."""
    monkeypatch.delenv("SSN_SHADOW_MODEL_DIR", raising=False)
