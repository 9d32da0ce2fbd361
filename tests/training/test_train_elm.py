"""Batched ELM sampling and rendering agree with the engine's LightMap and render_light_map."""

from __future__ import annotations

import numpy as np
import pytest

from ssn_engine.hemisphere import render_light_map
from ssn_engine.light_map import MAX_LIGHTS, SOFTNESS_RANGE
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
    np.testing.assert_allclose(render_lights(lights, 16)[0], render_light_map(lights.light_map(0), 16), rtol=1e-4,
                               atol=1e-6)


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
