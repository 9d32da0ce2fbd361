"""The stable entry point ssn_engine.predict_frames (conventions.md)."""

from __future__ import annotations

import numpy as np
import pytest
from engine_helpers import drawn_alpha, elm_for, object_geometry
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

import ssn_engine
from ssn_engine import api
from ssn_engine.ao_edit import scale_strength
from ssn_engine.framing import frame_alpha
from ssn_engine.hemisphere import render_light_map
from ssn_engine.host_kit.light_map import GaussianLight, LightMap

N = 256


@pytest.fixture(autouse=True)
def _fresh_default_method():
    api.default_method.cache_clear()
    yield
    api.default_method.cache_clear()


@pytest.fixture(scope="module")
def masks(pawn_frame):
    post, _ = frame_alpha(drawn_alpha(160, 120), N)
    return np.stack([pawn_frame, post]).astype(np.float32)


def test_package_exports_predict_frames():
    assert ssn_engine.predict_frames is api.predict_frames


def test_shapes_dtype_and_range(masks):
    elms = np.stack([elm_for(0.3, 0.6), elm_for(0.5, 0.8)])
    s = ssn_engine.predict_frames(masks, elms)
    assert s.shape == (2, N, N) and s.dtype == np.float32
    assert 0.0 <= s.min() and s.max() <= 1.0
    assert s[0].max() > 0.5 and s[1].max() > 0.5
    # the second light is straight ahead: its shadow comes towards the viewer, below the base
    _, base, _ = object_geometry(masks[1])
    assert s[1, base + 5 :].sum() > 0.8 * (s[1] * (1 - masks[1])).sum()


def test_more_frames_than_one_batch(masks):
    n = api.BATCH + 2
    many = np.repeat(masks[:1], n, axis=0)
    elms = np.repeat(elm_for(0.3, 0.6)[None], n, axis=0)
    s = api.predict_frames(many, elms)
    assert s.shape == (n, N, N)
    assert np.allclose(s, s[0], atol=1e-6)  # the same input gives the same shadow in every batch


def test_accepts_other_dtypes(masks):
    elms = np.stack([elm_for(0.3, 0.6), elm_for(0.7, 0.6)])
    s32 = api.predict_frames(masks, elms)
    s64 = api.predict_frames(masks.astype(np.float64), elms.astype(np.float64))
    assert s64.dtype == np.float32 and np.allclose(s32, s64, atol=1e-5)


def test_ao_override_is_used(masks):
    elms = np.stack([elm_for(0.3, 0.6)] * 2)
    predicted = api.predict_frames(masks, elms)
    same = api.predict_frames(masks, elms, ao=api.default_method().method.predict_ao(masks))
    assert np.allclose(predicted, same, atol=1e-6)
    ao = api.default_method().method.predict_ao(masks)
    # the paper's user control: more occlusion near the contact darkens the shadow, none lightens it (the
    # geometry-guided SR takes the cast shadow from the card, so the AO steers less of it than it did)
    darker = api.predict_frames(masks, elms, ao=np.stack([scale_strength(a, 2.0) for a in ao]))
    lighter = api.predict_frames(masks, elms, ao=np.stack([scale_strength(a, 0.0) for a in ao]))
    assert darker.shape == (2, N, N) and darker.dtype == np.float32
    assert darker.mean() > 1.08 * predicted.mean() and lighter.mean() < 0.8 * predicted.mean()
    # out-of-range AO values are clipped, not propagated
    assert np.allclose(
        api.predict_frames(masks, elms, ao=np.full_like(masks, 5.0)),
        api.predict_frames(masks, elms, ao=np.ones_like(masks)),
        atol=1e-6,
    )


@pytest.mark.parametrize(
    "make, name",
    [
        (lambda m, e: (m[0], e), "masks"),
        (lambda m, e: (m[:, :128, :128], e), "masks"),
        (lambda m, e: (m[:, :, :200], e), "masks"),
        (lambda m, e: (m, e[:1]), "elms"),
        (lambda m, e: (m, e[:, :8]), "elms"),
        (lambda m, e: (m, e[0]), "elms"),
    ],
)
def test_bad_shapes(masks, make, name):
    elms = np.stack([elm_for(0.3, 0.6)] * 2)
    m, e = make(masks, elms)
    with pytest.raises(ValueError, match=name):
        api.predict_frames(m, e)


def test_bad_ao_shape(masks):
    elms = np.stack([elm_for(0.3, 0.6)] * 2)
    with pytest.raises(ValueError, match="ao"):
        api.predict_frames(masks, elms, ao=masks[:1])
    with pytest.raises(ValueError, match="ao"):
        api.predict_frames(masks, elms, ao=masks[:, :128, :128])


@pytest.mark.parametrize("where", ["masks", "elms", "ao"])
@pytest.mark.parametrize("bad", [np.nan, np.inf])
def test_non_finite_values(masks, where, bad):
    m, e, a = masks.copy(), np.stack([elm_for(0.3, 0.6)] * 2), np.ones_like(masks)
    {"masks": m, "elms": e, "ao": a}[where][0, 3, 5] = bad
    with pytest.raises(ValueError, match=where):
        api.predict_frames(m, e, ao=a)


def test_negative_elm(masks):
    e = np.stack([elm_for(0.3, 0.6)] * 2)
    e[1, 0, 0] = -0.01
    with pytest.raises(ValueError, match="elms"):
        api.predict_frames(masks, e)


# -- properties ----------------------------------------------------------------


@st.composite
def frame_masks(draw):
    """1-2 frames, each with an upright box or ellipse standing in the frame."""
    n = draw(st.integers(1, 2))
    out = np.zeros((n, N, N), np.float32)
    yy, xx = np.mgrid[0:N, 0:N]
    for i in range(n):
        kind = draw(st.sampled_from(["box", "ellipse", "empty"]))
        if kind == "empty":
            continue
        top = draw(st.integers(4, 120))
        height = draw(st.integers(2, 240 - top))
        half = draw(st.integers(1, 100))
        cx = draw(st.integers(110, 146))
        value = draw(st.floats(0.2, 1.0))
        if kind == "box":
            out[i, top : top + height, cx - half : cx + half] = value
        else:
            cy = top + height / 2
            inside = ((xx - cx) / half) ** 2 + ((yy - cy) / (height / 2)) ** 2 <= 1
            out[i][inside] = value
    return out


lights = st.builds(
    GaussianLight,
    u=st.floats(0.0, 1.0),
    v=st.floats(0.0, 1.0),
    softness=st.floats(1e-4, 0.1),
    intensity=st.floats(0.0, 3.0),
)


def _draw_frames(data, min_lights: int) -> tuple[np.ndarray, np.ndarray]:
    """Frames drawn from ``data``: (masks, one ELM a frame of ``min_lights`` to 3 lights)."""
    m = data.draw(frame_masks())
    light_lists = data.draw(
        st.lists(st.lists(lights, min_size=min_lights, max_size=3), min_size=len(m), max_size=len(m))
    )
    return m, np.stack([render_light_map(LightMap(ls)) for ls in light_lists]).astype(np.float32)


PROPERTY = settings(max_examples=6, deadline=None, suppress_health_check=[HealthCheck.too_slow])


@PROPERTY
@given(data=st.data())
def test_property_range_shape_and_inputs_unchanged(data):
    m, e = _draw_frames(data, min_lights=0)
    use_ao = data.draw(st.booleans())
    ao = np.clip(1.0 - 0.5 * m, 0, 1) if use_ao else None
    m0, e0 = m.copy(), e.copy()
    ao0 = None if ao is None else ao.copy()
    s = api.predict_frames(m, e, ao=ao)
    assert s.shape == m.shape and s.dtype == np.float32
    assert np.all(np.isfinite(s)) and s.min() >= 0.0 and s.max() <= 1.0
    assert np.array_equal(m, m0) and np.array_equal(e, e0)
    if ao is not None:
        assert np.array_equal(ao, ao0)
    for i in range(len(m)):
        if not e[i].any():
            assert not s[i].any()


@PROPERTY
@given(m=frame_masks())
def test_property_all_zero_elm_gives_no_shadow(m):
    s = api.predict_frames(m, np.zeros((len(m), 16, 32), np.float32))
    assert s.shape == m.shape and not s.any()


def test_an_empty_mask_casts_no_shadow():
    """Nothing to cast, no shadow: exactly zero (the network alone left a faint haze, up to 0.2)."""
    masks = np.zeros((2, N, N), np.float32)
    masks[1, 100:200, 120:136] = 1.0
    elms = np.zeros((2, 16, 32), np.float32)
    elms[:, 4, 10] = 3.0
    s = api.predict_frames(masks, elms)
    assert not s[0].any() and s[1].max() > 0.3


@PROPERTY
@given(data=st.data())
def test_property_scaling_the_elm_does_not_change_the_shadow(data):
    m, e = _draw_frames(data, min_lights=1)
    k = data.draw(st.floats(1e-3, 1e3))
    assert np.allclose(api.predict_frames(m, k * e), api.predict_frames(m, e), atol=1e-4)


# -- camera input (conventions, "Camera input") ----------------------------------


def _default_camera(mask: np.ndarray) -> np.ndarray:
    """The camera input of the conventions' default camera (45 degrees, pitch 15) fitted to a mask."""
    from ssn_engine.camera import camera_for_span

    rows = np.flatnonzero((mask > 0.05).any(axis=1))
    cam, _ = camera_for_span(N, float(rows[0]), float(rows[-1] + 1))
    return np.array([cam.horizon, cam.focal])


def test_cameras_change_the_geometric_shadow_as_the_horizon_says(masks, monkeypatch):
    """Lower horizon = camera looking down less: the same sun's shadow on the ground looks shorter."""
    monkeypatch.setenv("SSN_SHADOW_MODEL_DIR", "/nonexistent")  # the geometric card: camera-aware by design
    elm = elm_for(0.0, 0.75)[None]  # behind the camera: the shadow falls away from the viewer
    m = masks[1:]
    level = api.predict_frames(m, elm, cameras=np.array([[60.0, 300.0]]))
    steep = api.predict_frames(m, elm, cameras=np.array([[-150.0, 300.0]]))
    _, base, _ = object_geometry(m[0])
    reach = [int(np.flatnonzero((s[0] * (1 - m[0]) > 0.2).any(axis=1)).min()) for s in (level, steep)]
    assert reach[0] > reach[1] + 3  # the shadow climbs higher up the frame when seen from above
    blind = api.predict_frames(m, elm)
    assert np.allclose(blind, api.predict_frames(m, elm, cameras=_default_camera(m[0])[None]), atol=0.02)


@pytest.mark.parametrize(
    "cameras, match",
    [
        (np.zeros((1, 2)), "cameras: expected shape"),
        (np.zeros((2, 3)), "cameras: expected shape"),
        (np.array([[10.0, 0.0], [10.0, 200.0]]), "focal"),
        (np.array([[np.nan, 200.0], [10.0, 200.0]]), "horizon rows"),
        (np.array([[10.0, 1e30], [10.0, 200.0]]), "1 to 170 degrees"),
        (np.array([[1e6, 200.0], [10.0, 200.0]]), "within 100 frames"),
    ],
)
def test_bad_cameras(masks, cameras, match):
    with pytest.raises(ValueError, match=match):
        api.predict_frames(masks, np.stack([elm_for(0.3, 0.6)] * 2), cameras=cameras)
