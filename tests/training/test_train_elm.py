"""Batched ELM sampling and rendering agree with the engine's LightMap and render_light_map."""

from __future__ import annotations

import numpy as np
import pytest

from ssn_engine.hemisphere import render_light_map
from ssn_engine.host_kit.light_map import MAX_LIGHTS, SOFTNESS_RANGE
from training.elm import render_lights, sample_lights


@pytest.mark.parametrize("h", [4, 16])
def test_render_lights_matches_engine(h):
    lights = sample_lights(np.random.default_rng(0), 12)
    got = render_lights(lights, h)
    for b in range(len(lights)):
        ref = render_light_map(lights.light_map(b), h)
        np.testing.assert_allclose(got[b], ref, rtol=1e-4, atol=1e-6 * max(ref.max(), 1.0))


def test_wrapping_light_at_the_seam():
    lights = sample_lights(np.random.default_rng(1), 1)
    lights.u[:] = 0.999
    lights.softness[:] = 0.05
    np.testing.assert_allclose(
        render_lights(lights, 16)[0], render_light_map(lights.light_map(0), 16), rtol=1e-4, atol=1e-6
    )


def test_sampling_follows_table_1():
    lights = sample_lights(np.random.default_rng(2), 2000)
    k = lights.active.sum(axis=1)
    assert k.min() >= 1 and k.max() <= MAX_LIGHTS and k.max() > 40
    on = lights.active
    assert lights.intensity[on].min() >= 0 and lights.intensity[on].max() <= 3
    assert np.all(lights.intensity[~on] == 0)
    assert lights.softness[on].min() >= SOFTNESS_RANGE[0] and lights.softness[on].max() <= SOFTNESS_RANGE[1]
    assert 0 <= lights.u.min() and lights.u.max() <= 1 and 0 <= lights.v.min() and lights.v.max() <= 1


def test_sampling_is_seeded():
    a = render_lights(sample_lights(np.random.default_rng(5), 3), 16)
    b = render_lights(sample_lights(np.random.default_rng(5), 3), 16)
    np.testing.assert_array_equal(a, b)


def test_light_families_follow_their_definitions():
    from training.elm import sample_family

    rng = np.random.default_rng(3)
    sun = sample_family(rng, 500, "sun")
    assert np.all(sun.active.sum(axis=1) == 1)
    elevation = 90.0 * (1.0 - sun.v[:, 0])
    assert elevation.min() >= 5.0 and elevation.max() <= 80.0
    assert sun.softness[:, 0].max() <= 0.005 and sun.u[:, 0].min() < 0.05 and sun.u[:, 0].max() > 0.95
    assert np.all(sample_family(rng, 50, "two").active.sum(axis=1) == 2)
    sky = sample_family(rng, 500, "sky")
    k = sky.active.sum(axis=1)
    assert k.min() == 3 and k.max() == 8
    assert sky.softness[sky.active].min() >= 0.03 and sky.softness[sky.active].max() <= 0.1
    for family in ("sun", "two", "sky", "table1"):  # absent lights stay dark, every map renders finite
        lb = sample_family(rng, 20, family)
        assert np.all(lb.intensity[~lb.active] == 0) and np.all(np.isfinite(render_lights(lb, 16)))
    with pytest.raises(ValueError, match="family"):
        sample_family(rng, 1, "moon")


def test_the_training_mixture_draws_every_family():
    from training.elm import TRAIN_MIX, sample_mixture

    lights = sample_mixture(np.random.default_rng(4), 4000, TRAIN_MIX)
    k = lights.active.sum(axis=1)
    share_one = np.mean(k == 1)  # suns, plus Table 1 maps that drew one light (1 in 50 of them)
    assert share_one == pytest.approx(TRAIN_MIX["sun"] + TRAIN_MIX["table1"] / 50, abs=0.03)
    assert np.mean(k > 8) == pytest.approx(TRAIN_MIX["table1"] * 42 / 50, abs=0.03)
