"""Light-map JSON, AO edit lists and predict_frames inputs under random values: a result, or the documented
error (LightMapError, AOEditError, ValueError), never anything else."""

from __future__ import annotations

import json

import numpy as np
from fuzz_settings import FUZZ
from hypothesis import given
from hypothesis import strategies as st

from ssn_engine import predict_frames
from ssn_engine.ao_edit import AOEditError, apply_edits
from ssn_engine.host_kit.light_map import MAX_LIGHTS, LightMap, LightMapError

numbers = (
    st.floats(allow_nan=True, allow_infinity=True)
    | st.integers(-(10**6), 10**6)
    | st.text(max_size=4)
    | st.none()
    | st.booleans()
)
light = st.dictionaries(st.sampled_from(["u", "v", "softness", "intensity", "x"]), numbers, max_size=5)
light_maps = st.fixed_dictionaries(
    {},
    optional={
        "format": st.sampled_from(["ssn-shadow-elm", "elm", 1]),
        "version": st.sampled_from([1, 2, "1", None]),
        "lights": st.lists(light | numbers, max_size=MAX_LIGHTS + 2) | numbers,
    },
)


@FUZZ
@given(data=light_maps | st.text(max_size=40), as_text=st.booleans())
def test_light_map_json(data, as_text):
    text = data if isinstance(data, str) else json.dumps(data)
    try:
        lights = LightMap.from_json(text) if as_text or isinstance(data, str) else LightMap.from_dict(data)
    except LightMapError as exc:
        assert str(exc)
        return
    assert len(lights) <= MAX_LIGHTS and LightMap.from_json(lights.to_json()).to_dict() == lights.to_dict()


edit = st.fixed_dictionaries(
    {"op": st.sampled_from(["brush", "grow", "strength", "blur"]) | numbers},
    optional={"x": numbers, "y": numbers, "radius": numbers, "strength": numbers, "pixels": numbers, "value": numbers},
)
AO = np.linspace(0, 1, 64 * 64, dtype=np.float32).reshape(64, 64)


@FUZZ
@given(edits=st.lists(edit | numbers, max_size=4) | numbers)
def test_ao_edit_lists(edits):
    try:
        out = apply_edits(AO, edits)
    except AOEditError as exc:
        assert str(exc)
        return
    assert out.shape == AO.shape and np.all(np.isfinite(out)) and out.min() >= 0 and out.max() <= 1


FILL = {
    "zeros": lambda r, s: np.zeros(s),
    "ones": lambda r, s: np.ones(s),
    "random": lambda r, s: r.random(s),
    "blob": lambda r, s: (r.random(s) > 0.7).astype(float),
    "negative": lambda r, s: -r.random(s),
    "huge": lambda r, s: r.random(s) * 1e30,
    "nan": lambda r, s: np.where(r.random(s) > 0.99, np.nan, 0.5),
    "inf": lambda r, s: np.full(s, np.inf),
}


@st.composite
def arrays(draw, shape):
    """An array of a valid or a wrong shape, one of FILL's kinds, of a random dtype."""
    if draw(st.integers(0, 5)) == 0:
        shape = tuple(draw(st.lists(st.integers(0, 3), max_size=4)))
    rng = np.random.default_rng(draw(st.integers(0, 2**32 - 1)))
    dtype = draw(st.sampled_from([np.float32, np.float64, np.float16, np.uint8, np.int64]))
    with np.errstate(all="ignore"):
        return FILL[draw(st.sampled_from(sorted(FILL)))](rng, shape).astype(dtype)


@FUZZ
@given(data=st.data(), n=st.integers(1, 2))
def test_predict_frames_inputs(data, n):
    masks = data.draw(arrays((n, 256, 256)))
    elms = data.draw(arrays((n, 16, 32)))
    ao = data.draw(st.none() | arrays((n, 256, 256)))
    cameras = data.draw(st.none() | arrays((n, 2)))
    try:
        s = predict_frames(masks, elms, ao=ao, cameras=cameras)
    except ValueError as exc:
        assert str(exc)
        return
    assert s.shape == (len(masks), 256, 256) and s.dtype == np.float32
    assert np.all(np.isfinite(s)) and s.min() >= 0 and s.max() <= 1
