"""User AO edits (ssn_engine.ao_edit)."""

from __future__ import annotations

import numpy as np
import pytest

from ssn_engine.ao_edit import AOEditError, apply_edits

N = 64


def _ao():
    """An AO map with a dark contact blob in the middle (1 = fully open)."""
    yy, xx = np.mgrid[0:N, 0:N]
    d = np.hypot(xx - 32, yy - 40) / 10
    return np.clip(0.4 + 0.6 * d, 0, 1).astype(np.float32)


def _dist(x, y):
    yy, xx = np.mgrid[0:N, 0:N]
    return np.hypot(xx + 0.5 - x * N, yy + 0.5 - y * N)


def test_darken_brush_is_local():
    ao = _ao()
    out = apply_edits(ao, [{"op": "brush", "x": 0.25, "y": 0.25, "radius": 0.1, "strength": -0.7}])
    d = _dist(0.25, 0.25)
    inside, outside = d < 0.1 * N * 0.9, d >= 0.1 * N
    assert np.all(out[inside] < ao[inside])
    assert out[inside].min() == pytest.approx(0.3 * ao[int(0.25 * N), int(0.25 * N)], abs=0.02)  # centre: 70 % darker
    assert np.array_equal(out[outside], ao[outside])
    assert out.dtype == np.float32 and out.shape == ao.shape


def test_lighten_brush_is_local_and_stays_in_range():
    ao = _ao()
    out = apply_edits(ao, [{"op": "brush", "x": 0.5, "y": 40 / N, "radius": 0.2, "strength": 1.0}])
    d = _dist(0.5, 40 / N)
    assert out[40, 32] == pytest.approx(1.0, abs=0.01)  # full strength at the centre: fully open
    assert np.all(out[d < 0.2 * N] >= ao[d < 0.2 * N])
    assert np.array_equal(out[d >= 0.2 * N], ao[d >= 0.2 * N])
    assert out.max() <= 1.0


def test_brush_strength_zero_changes_nothing():
    ao = _ao()
    assert np.array_equal(apply_edits(ao, [{"op": "brush", "x": 0.5, "y": 0.5, "radius": 0.3, "strength": 0.0}]), ao)


def test_brush_partly_off_the_frame():
    ao = np.ones((N, N), np.float32)
    out = apply_edits(ao, [{"op": "brush", "x": -0.05, "y": 1.02, "radius": 0.2, "strength": -1.0}])
    assert out[-1, 0] < 0.5 and out[0, -1] == 1.0


def test_grow_and_shrink_the_dark_region():
    ao = np.ones((N, N), np.float32)
    ao[30:34, 30:34] = 0.2
    grown = apply_edits(ao, [{"op": "grow", "pixels": 3}])
    shrunk = apply_edits(ao, [{"op": "grow", "pixels": -1}])
    assert (grown < 0.5).sum() > (ao < 0.5).sum() > (shrunk < 0.5).sum()
    assert grown[30:34, 27].max() < 0.5 and grown[30:34, 36].max() < 0.5  # 3 pixels beyond the block
    assert grown[30:34, 25].min() == 1.0  # but not 5
    assert (shrunk < 0.5).sum() == 4  # a 4 x 4 block shrunk by 1 pixel
    assert np.array_equal(apply_edits(ao, [{"op": "grow", "pixels": 0}]), ao)


def test_strength_scales_the_occlusion():
    ao = _ao()
    none = apply_edits(ao, [{"op": "strength", "value": 0}])
    assert np.all(none == 1.0)  # 0 removes all occlusion
    same = apply_edits(ao, [{"op": "strength", "value": 1}])
    assert np.allclose(same, ao)
    half = apply_edits(ao, [{"op": "strength", "value": 0.5}])
    assert np.allclose(1 - half, 0.5 * (1 - ao), atol=1e-6)
    double = apply_edits(ao, [{"op": "strength", "value": 2}])
    assert np.allclose(1 - double, np.clip(2 * (1 - ao), 0, 1), atol=1e-6)


def test_edits_apply_in_order_and_do_not_modify_the_input():
    ao = _ao()
    before = ao.copy()
    brush = {"op": "brush", "x": 0.5, "y": 0.5, "radius": 0.2, "strength": -0.5}
    a = apply_edits(ao, [brush, {"op": "strength", "value": 0}])
    b = apply_edits(ao, [{"op": "strength", "value": 0}, brush])
    assert np.all(a == 1.0)  # removing occlusion last wipes the brush too
    assert b.min() < 0.6
    assert np.array_equal(ao, before)
    assert np.array_equal(apply_edits(ao, []), ao)


@pytest.mark.parametrize(
    "edits, pattern",
    [
        ([{"op": "brush", "x": 0.5, "y": 0.5, "radius": 0.1}], r"edits\[0\]\.strength"),
        (
            [{"op": "strength", "value": 1}, {"op": "brush", "x": "a", "y": 0.5, "radius": 0.1, "strength": 1}],
            r"edits\[1\]\.x",
        ),
        ([{"op": "brush", "x": 0.5, "y": 0.5, "radius": 0.1, "strength": -2}], r"edits\[0\]\.strength.*-2"),
        ([{"op": "brush", "x": 0.5, "y": float("nan"), "radius": 0.1, "strength": 1}], r"edits\[0\]\.y"),
        ([{"op": "brush", "x": 0.5, "y": 0.5, "radius": True, "strength": 1}], r"edits\[0\]\.radius"),
        ([{"op": "grow", "pixels": 100}], r"edits\[0\]\.pixels"),
        ([{"op": "grow"}], r"edits\[0\]\.pixels"),
        ([{"op": "strength", "value": -1}], r"edits\[0\]\.value"),
        ([{"op": "blur"}], r"edits\[0\]\.op.*blur"),
        ([{}], r"edits\[0\]\.op"),
        ([{"op": "grow", "pixels": 1}, "grow"], r"edits\[1\]: expected an object"),
    ],
)
def test_malformed_edits_name_the_field(edits, pattern):
    with pytest.raises(AOEditError, match=pattern):
        apply_edits(_ao(), edits)
