"""Shadow layers and composites (ssn_engine.compositing)."""

from __future__ import annotations

import numpy as np
import pytest

from ssn_engine.compositing import (
    HORIZON_RGB,
    READ_HORIZON_RGB,
    composite_shadow,
    from_unit_float,
    over,
    preview_image,
    shadow_layer,
    to_unit_float,
)
from ssn_engine.framing import CanvasShadow, frame_alpha, shadow_to_canvas


def _shadow():
    s = np.linspace(0, 1, 12, dtype=np.float32).reshape(3, 4)
    s[0, 0] = -0.5  # out-of-range values are clipped
    s[2, 3] = 1.5
    return s


@pytest.mark.parametrize("dtype, top", [("uint8", 255), ("uint16", 65535), ("float16", 1.0), ("float32", 1.0)])
def test_layer_dtypes_and_alpha(dtype, top):
    s = _shadow()
    layer = shadow_layer(s, (0.2, 0.4, 0.6), 0.5, dtype)
    assert layer.shape == (3, 4, 4) and layer.dtype == np.dtype(dtype)
    alpha = layer[..., 3].astype(np.float64) / top
    tol = 0.5 / top if top > 1 else 1e-3
    assert np.allclose(alpha, 0.5 * np.clip(s, 0, 1), atol=tol)
    assert np.allclose(layer[..., :3].astype(np.float64) / top, [0.2, 0.4, 0.6], atol=tol)


def test_rgba_and_bgra_order():
    s = np.full((2, 2), 0.5, np.float32)
    rgba = shadow_layer(s, (1.0, 0.5, 0.0), 1.0, "uint8", "rgba")
    bgra = shadow_layer(s, (1.0, 0.5, 0.0), 1.0, "uint8", "bgra")
    assert tuple(rgba[0, 0]) == (255, 128, 0, 128)
    assert tuple(bgra[0, 0]) == (0, 128, 255, 128)


def test_default_layer_is_black_uint8_rgba():
    layer = shadow_layer(np.array([[0.0, 1.0]], np.float32))
    assert layer.dtype == np.uint8
    assert layer.tolist() == [[[0, 0, 0, 0], [0, 0, 0, 255]]]


@pytest.mark.parametrize("dtype, top", [("uint8", 255), ("uint16", 65535), ("float16", 1.0), ("float32", 1.0)])
@pytest.mark.parametrize("color", [(0.0, 0.0, 0.0), (0.1, 0.3, 0.9)])
def test_a_large_canvas_layer_is_made_from_the_frame_as_from_its_values(dtype, top, color):
    """A frame enlarged onto a large canvas makes its layer band by band from the frame rows (no canvas-sized
    float array): the same layer, within one step of rounding, as the one made from all its values."""
    alpha = np.zeros((1500, 2000), np.uint8)
    alpha[300:1200, 800:1300] = 255
    _, framing = frame_alpha(alpha, 128)
    frame = np.random.default_rng(1).random((128, 128)).astype(np.float32)
    shadow = shadow_to_canvas(frame, framing)
    assert framing.scale < 1 and shadow.shape[0] > 1000
    layer = shadow_layer(shadow, color, 0.7, dtype, "bgra")
    expected = shadow_layer(shadow.values.copy(), color, 0.7, dtype, "bgra")
    assert layer.dtype == expected.dtype and layer.shape == shadow.shape + (4,)
    step = 1.0 if top > 1 else (1e-3 if dtype == "float16" else 1e-6)
    assert np.abs(layer.astype(np.float64) - expected.astype(np.float64)).max() <= step
    # and into a view of a larger layer, leaving the rest alone
    big = np.zeros((shadow.shape[0] + 4, shadow.shape[1] + 6, 4), dtype)
    shadow_layer(shadow, color, 0.7, dtype, "bgra", out=big[2:-2, 3:-3])
    assert np.array_equal(big[2:-2, 3:-3], layer) and not big[:2].any() and not big[:, :3].any()
    with pytest.raises(ValueError, match="out"):
        shadow_layer(shadow, color, 0.7, dtype, out=big)


@pytest.mark.parametrize(
    "kwargs, pattern",
    [
        (dict(color=(1.2, 0, 0)), "color"),
        (dict(color=(0, 0)), "color"),
        (dict(color=(0, float("nan"), 0)), "color"),
        (dict(opacity=1.5), "opacity"),
        (dict(opacity=-0.1), "opacity"),
        (dict(opacity=float("nan")), "opacity"),
        (dict(dtype="int32"), "dtype"),
        (dict(channels="argb"), "channels"),
    ],
)
def test_bad_layer_arguments(kwargs, pattern):
    with pytest.raises(ValueError, match=pattern):
        shadow_layer(np.zeros((2, 2), np.float32), **kwargs)


@pytest.mark.parametrize("opacity", [1.0, 0.6])
def test_black_multiply_equals_background_times_one_minus_opacity_s(opacity):
    rng = np.random.default_rng(0)
    bg = rng.random((5, 6, 3)).astype(np.float32)
    s = rng.random((5, 6)).astype(np.float32)
    out = composite_shadow(bg, s, (0, 0, 0), opacity)
    assert out.dtype == np.float32
    assert np.allclose(out, bg * (1 - opacity * s)[..., None], atol=1e-6)
    # the layer in Multiply mode over the background gives the same composite
    layer = shadow_layer(s, (0, 0, 0), opacity, "float32")
    a = layer[..., 3:4]
    multiply = bg * (1 - a) + bg * layer[..., :3] * a
    assert np.allclose(multiply, out, atol=1e-6)


def test_coloured_composite_and_alpha_channel_kept():
    bg = np.full((2, 2, 4), 200, np.uint8)
    bg[..., 3] = 77
    s = np.array([[0.0, 0.5], [1.0, 1.0]], np.float32)
    out = composite_shadow(bg, s, (0.5, 1.0, 0.0), 1.0)
    assert out.dtype == np.uint8
    assert np.all(out[..., 3] == 77)
    assert tuple(out[0, 0, :3]) == (200, 200, 200)
    assert tuple(out[1, 0, :3]) == (100, 200, 0)  # full shadow tinted: background * colour
    assert tuple(out[0, 1, :3]) == (150, 200, 100)


def test_uint16_composite():
    bg = np.full((1, 2, 3), 40000, np.uint16)
    out = composite_shadow(bg, np.array([[0.0, 0.25]], np.float32))
    assert out.dtype == np.uint16
    assert out[0, 0].tolist() == [40000] * 3 and out[0, 1].tolist() == [30000] * 3


def test_composite_size_mismatch():
    with pytest.raises(ValueError, match="size"):
        composite_shadow(np.zeros((4, 4, 3), np.uint8), np.zeros((4, 5), np.float32))


def test_over_leaves_opaque_cutout_pixels_exact():
    rng = np.random.default_rng(1)
    bg = rng.integers(0, 256, (6, 7, 3), dtype=np.uint8)
    cut = rng.integers(0, 256, (6, 7, 4), dtype=np.uint8)
    cut[..., 3] = 0
    cut[2:4, 2:5, 3] = 255
    cut[5, 5, 3] = 128
    out = over(bg, cut)
    assert out.dtype == np.uint8
    assert np.array_equal(out[2:4, 2:5], cut[2:4, 2:5, :3])  # the cutout's own pixels never change
    transparent = cut[..., 3] == 0
    assert np.array_equal(out[transparent], bg[transparent])
    expected = np.rint(cut[5, 5, :3] * (128 / 255) + bg[5, 5] * (127 / 255))
    assert np.allclose(out[5, 5], expected, atol=1)


def test_shadow_under_the_cutout_never_shows_through_it():
    bg = np.full((4, 4, 3), 220, np.uint8)
    cut = np.zeros((4, 4, 4), np.uint8)
    cut[1:3, 1:3] = (10, 20, 30, 255)
    shaded = composite_shadow(bg, np.ones((4, 4), np.float32), (0, 0, 0), 1.0)
    out = over(shaded, cut)
    assert np.all(out[1:3, 1:3] == (10, 20, 30))
    assert np.all(out[0] == 0)


def test_over_rgba_background_and_errors():
    bg = np.zeros((2, 2, 4), np.uint8)
    cut = np.zeros((2, 2, 4), np.uint8)
    cut[0, 0] = (255, 0, 0, 255)
    out = over(bg, cut)
    assert out[0, 0].tolist() == [255, 0, 0, 255] and out[1, 1].tolist() == [0, 0, 0, 0]
    with pytest.raises(ValueError):
        over(bg, cut[..., :3])
    with pytest.raises(ValueError):
        over(bg, np.zeros((3, 2, 4), np.uint8))


def test_unit_float_round_trips():
    for dtype in (np.uint8, np.uint16):
        top = np.iinfo(dtype).max
        values = np.array([0, 1, top // 2, top], dtype)
        assert np.array_equal(from_unit_float(to_unit_float(values), dtype), values)
    f = to_unit_float(np.array([np.nan, -1.0, 0.25, 2.0], np.float32))
    assert f.tolist() == [0.0, 0.0, 0.25, 1.0]
    with pytest.raises(ValueError, match="dtype"):
        from_unit_float(np.zeros(2, np.float32), np.int16)


def test_preview_image_multiplies_hides_under_the_cutout_and_draws_the_horizon():
    bg = np.array([[[200, 200, 200, 255], [100, 100, 100, 255]]], np.uint8)  # 2 x 1 RGBA
    green = preview_image(bg, CanvasShadow(np.ones((1, 1), np.float32), 1, 0), color=(0.0, 1.0, 0.0))
    assert green.tolist() == [[[200, 200, 200], [0, 100, 0]]]
    half = preview_image(bg, CanvasShadow(np.full((1, 1), 0.5, np.float32), 0, 0))
    assert half.tolist() == [[[100, 100, 100], [100, 100, 100]]]
    # the cutout above the shadow layer hides it: fully where opaque, half where half transparent
    covered = preview_image(bg, CanvasShadow(np.ones((1, 2), np.float32), 0, 0), np.array([[255, 128]], np.uint8))
    assert covered.tolist() == [[[200, 200, 200], [50, 50, 50]]]
    # a shadow hanging off the image is clipped
    assert preview_image(bg, CanvasShadow(np.ones((2, 2), np.float32), 1, -1))[0, 1].tolist() == [0, 0, 0]
    rgb = np.zeros((10, 20, 3), np.uint8)
    lined = preview_image(rgb, CanvasShadow(np.zeros((0, 0), np.float32), 0, 0), horizon=4.6)
    assert tuple(lined[4, 0]) == HORIZON_RGB and lined[4, 6].tolist() == [0, 0, 0]  # a dash, then a gap
    assert lined[:4].max() == 0 and lined[5:].max() == 0  # only that row
    for outside in (-3.0, 10.0):
        assert preview_image(rgb, CanvasShadow(np.zeros((0, 0), np.float32), 0, 0), horizon=outside).max() == 0
    # the horizon the model read, not one the artist set: dotted, in another colour
    dotted = preview_image(rgb, CanvasShadow(np.zeros((0, 0), np.float32), 0, 0), horizon=4.6, read=True)
    assert tuple(dotted[4, 0]) == READ_HORIZON_RGB and dotted[4, 1].tolist() == [0, 0, 0]
    assert tuple(dotted[4, 6]) == READ_HORIZON_RGB and HORIZON_RGB not in [tuple(p) for p in dotted[4]]
