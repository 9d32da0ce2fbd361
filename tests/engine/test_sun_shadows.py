"""The shipped model's shadows follow the light: single suns on fixed masks and on held-out shapes.

``tests/data/sun_views.npz`` holds twelve test-split views (objects, animals, people at pitches 0 to 30) with
their exact shadows under three suns (tools/make_sun_fixture.py); the geometric measures are those of
docs/benchmark.md (training.metrics.sun_geometry).
"""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest
from engine_helpers import drawn_alpha, elm_for

from ssn_engine import api
from ssn_engine.framing import frame_alpha
from ssn_engine.hemisphere import render_light_map
from ssn_engine.light_map import GaussianLight, LightMap
from training.metrics import shadow_direction, shadow_extent, sun_geometry

FIXTURE = Path(__file__).resolve().parents[1] / "data" / "sun_views.npz"


@pytest.fixture(autouse=True)
def _shipped_model(monkeypatch):
    monkeypatch.delenv("SSN_SHADOW_MODEL_DIR", raising=False)
    api.default_method.cache_clear()
    yield
    api.default_method.cache_clear()


@pytest.fixture(scope="module")
def fixed_masks(pawn_frame):
    post, _ = frame_alpha(drawn_alpha(160, 120), 256)
    return {"pawn": pawn_frame, "post": post}


def sun(u: float, elevation: float) -> np.ndarray:
    return render_light_map(LightMap([GaussianLight(u, 1.0 - elevation / 90.0, 0.002, 1.0)]), 16)


@pytest.mark.parametrize("name", ["pawn", "post"])
@pytest.mark.parametrize("u", [0.25, 0.75])
def test_a_lower_sun_casts_a_longer_shadow(fixed_masks, name, u):
    mask = fixed_masks[name]
    s = api.predict_frames(np.repeat(mask[None], 3, 0), np.stack([sun(u, e) for e in (60.0, 35.0, 15.0)]))
    direction = shadow_direction(s[-1], mask)
    assert direction is not None
    assert (direction[0] > 0) == (u < 0.5)  # a light left of forward casts to the right, and vice versa
    reach = [shadow_extent(x, mask, direction) for x in s]
    assert reach[0] * 1.15 < reach[1] and reach[1] * 1.15 < reach[2], reach


@pytest.mark.parametrize("name", ["pawn", "post"])
def test_a_mirrored_light_gives_the_mirrored_shadow(fixed_masks, name):
    mask = fixed_masks[name]
    elm = sun(0.7, 30.0)
    s = api.predict_frames(np.stack([mask, mask[:, ::-1]]), np.stack([elm, elm[:, ::-1]]))
    assert np.abs(s[1] - s[0][:, ::-1]).max() < 0.02


def test_sun_shadow_length_on_held_out_shapes():
    data = np.load(FIXTURE)
    masks = data["masks"].astype(np.float32) / 255
    truth = data["shadows"].astype(np.float32) / 255
    n_views, n_suns = truth.shape[:2]
    elms = np.stack([sun(u, e) for u, e in data["suns"]])
    pred = api.predict_frames(np.repeat(masks, n_suns, 0), np.tile(elms, (n_views, 1, 1)))
    pred = pred.reshape(n_views, n_suns, *masks.shape[1:])
    geometry = [sun_geometry(pred[v, k], truth[v, k], masks[v]) for v in range(n_views) for k in range(n_suns)]
    geometry = [g for g in geometry if g is not None]
    assert len(geometry) >= n_views * n_suns // 2
    ratio = float(np.median([g["length_ratio"] for g in geometry]))
    error = float(np.median([g["direction_error"] for g in geometry]))
    assert 0.7 <= ratio <= 1.4, ratio
    assert error <= 20.0, error


def test_elm_for_helper_is_a_single_small_light():
    assert elm_for(0.5, 0.5).max() > 0 and (elm_for(0.5, 0.5) > 0.01 * elm_for(0.5, 0.5).max()).sum() < 40
