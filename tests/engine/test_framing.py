"""Canvas alpha <-> N x N frame (ssn_engine.framing)."""

from __future__ import annotations

import tracemalloc

import numpy as np
import pytest
from engine_helpers import drawn_alpha

from ssn_engine.camera import top_row
from ssn_engine.framing import (
    OBJECT_EXTENT,
    EmptyAlphaError,
    alpha_bbox,
    edge_fade,
    fade_at_edges,
    frame_alpha,
    shadow_to_canvas,
)


def _visible_rows_cols(mask, threshold=0.02):
    rows = np.flatnonzero(mask.max(axis=1) > threshold)
    cols = np.flatnonzero(mask.max(axis=0) > threshold)
    return rows, cols


@pytest.mark.parametrize("n", [256, 128, 64])
def test_object_top_row_and_horizontal_centre(n):
    mask, framing = frame_alpha(drawn_alpha(160, 120), n)
    assert mask.shape == (n, n) and mask.dtype == np.float32
    assert 0.0 <= mask.min() and mask.max() <= 1.0
    rows, cols = _visible_rows_cols(mask)
    assert rows[0] == top_row(n)
    # centred: the left and right margins differ by at most one pixel
    assert abs(cols[0] - (n - 1 - cols[-1])) <= 1
    # the larger side of the bbox spans OBJECT_EXTENT of the frame
    x0, y0, x1, y1 = framing.bbox
    assert max(x1 - x0, y1 - y0) * framing.scale == pytest.approx(OBJECT_EXTENT * n)
    assert abs(len(rows) - OBJECT_EXTENT * n) <= 2


def test_pawn_frame_top_and_centre(pawn_frame):
    rows, cols = _visible_rows_cols(pawn_frame)
    assert rows[0] == 8
    assert abs(cols[0] - (255 - cols[-1])) <= 1
    assert rows[-1] < 200  # ground below the object holds the shadow


def _place(shape, canvas_hw, at, dtype):
    """The drawn shape (as float in [0, 1]) on a canvas of canvas_hw at (x, y), in dtype."""
    small = drawn_alpha(*shape, dtype=np.float32)
    canvas = np.zeros(canvas_hw, np.float32)
    x, y = at
    canvas[y : y + small.shape[0], x : x + small.shape[1]] = small
    if dtype == np.uint8:
        return np.rint(canvas * 255).astype(np.uint8)
    if dtype == np.uint16:
        return np.rint(canvas * 65535).astype(np.uint16)
    out = canvas.astype(dtype)
    out[out == 0] = np.nan  # float alpha may carry NaN outside the cutout
    return out


@pytest.mark.parametrize(
    "canvas_hw, at, dtype",
    [
        ((120, 160), (0, 0), np.uint8),
        ((500, 300), (100, 250), np.uint8),
        ((130, 900), (700, 5), np.uint16),
        ((121, 161), (1, 1), np.float32),
        ((400, 400), (200, 150), np.float32),
    ],
)
def test_any_canvas_size_position_and_dtype_frame_alike(canvas_hw, at, dtype):
    reference, ref_framing = frame_alpha(drawn_alpha(160, 120), 128)
    alpha = _place((160, 120), canvas_hw, at, dtype)
    mask, framing = frame_alpha(alpha, 128)
    assert mask.dtype == np.float32 and np.all(np.isfinite(mask))
    assert np.abs(mask - reference).max() < 2e-3
    x, y = at
    x0, y0, x1, y1 = ref_framing.bbox
    assert framing.bbox == (x0 + x, y0 + y, x1 + x, y1 + y)
    assert (framing.canvas_width, framing.canvas_height) == (canvas_hw[1], canvas_hw[0])
    # the canvas point of the bbox's top-left corner lands at the same frame point
    assert framing.to_frame(x0 + x, y0 + y) == pytest.approx(ref_framing.to_frame(x0, y0))


def test_to_frame_and_to_canvas_are_inverse():
    _, framing = frame_alpha(_place((160, 120), (700, 900), (300, 200), np.uint8), 256)
    for x, y in [(0, 0), (333.5, 277.25), (899, 699)]:
        assert framing.to_canvas(*framing.to_frame(x, y)) == pytest.approx((x, y))


def test_float_alpha_values_are_clipped_and_nan_is_transparent():
    alpha = np.full((50, 60), np.nan, np.float32)
    alpha[10:40, 20:30] = 3.0  # over-range: counts as fully opaque
    alpha[10:40, 30:35] = -1.0  # under-range: transparent
    mask, framing = frame_alpha(alpha, 64)
    assert framing.bbox == (20, 10, 30, 40)
    assert mask.max() == pytest.approx(1.0) and mask.min() == 0.0
    assert np.all(np.isfinite(mask))


def test_alpha_below_threshold_is_background():
    alpha = np.full((40, 40), 2, np.uint8)  # 2/255 < 1 %: invisible haze
    alpha[10:20, 15:25] = 255
    assert alpha_bbox(alpha) == (15, 10, 25, 20)


@pytest.mark.parametrize(
    "alpha",
    [
        np.zeros((30, 40), np.uint8),
        np.zeros((30, 40), np.uint16),
        np.zeros((30, 40), np.float32),
        np.full((30, 40), np.nan, np.float32),
        np.full((30, 40), 1, np.uint8),
    ],
    ids=["uint8", "uint16", "float32", "nan", "haze"],
)
def test_empty_alpha_raises(alpha):
    with pytest.raises(EmptyAlphaError, match="empty"):
        frame_alpha(alpha)


@pytest.mark.parametrize("alpha", [np.zeros((0, 5), np.uint8), np.zeros((4, 4, 4), np.uint8)])
def test_malformed_alpha_raises_value_error(alpha):
    with pytest.raises(ValueError, match="alpha"):
        frame_alpha(alpha)


def test_tiny_masks():
    """A cutout under MIN_CUTOUT pixels casts no visible shadow: refused with its size; a 3 px one is framed."""
    alpha = np.zeros((300, 200), np.uint8)
    alpha[150, 120] = 255
    with pytest.raises(EmptyAlphaError, match="only 1 x 1 pixels"):
        frame_alpha(alpha, 256)
    alpha[150:153, 120] = 255
    mask, framing = frame_alpha(alpha, 256)
    assert framing.bbox == (120, 150, 121, 153)
    rows, cols = _visible_rows_cols(mask)
    assert rows[0] == top_row(256)
    assert abs(cols[0] - (255 - cols[-1])) <= 1
    assert mask.max() > 0.5


def test_fully_opaque_canvas():
    alpha = np.full((90, 160), 255, np.uint8)
    mask, framing = frame_alpha(alpha, 128)
    assert framing.bbox == (0, 0, 160, 90)
    rows, cols = _visible_rows_cols(mask, 0.5)
    assert rows[0] == top_row(128)
    assert len(cols) == 64 and len(rows) == 36
    assert mask[rows[0] + 1 : rows[-1], cols[0] + 1 : cols[-1]].min() > 0.99  # edges are filtered


def test_edge_fade_is_one_inside_and_falls_to_zero_at_the_edges():
    f = edge_fade(256)
    assert f.shape == (256, 256)
    assert f[128, 128] == 1.0 and f[20:236, 20:236].min() == 1.0
    assert f[0].max() < 0.1 and f[:, -1].max() < 0.1
    assert np.all(np.diff(f[128, :128]) >= 0)


@pytest.mark.parametrize("canvas_hw, at", [((120, 160), (0, 0)), ((600, 800), (390, 420)), ((300, 1000), (30, 150))])
def test_shadow_to_canvas_puts_a_frame_image_back_in_place(canvas_hw, at):
    alpha = _place((160, 120), canvas_hw, at, np.uint8)
    mask, framing = frame_alpha(alpha, 256)
    back = shadow_to_canvas(mask, framing)
    assert not back.is_empty
    full = back.full_canvas(canvas_hw[1], canvas_hw[0])
    assert full.shape == canvas_hw and full.dtype == np.float32
    # the 'shadow' (the mask itself) lands on the alpha's bounding box
    x0, y0, x1, y1 = framing.bbox
    ys, xs = np.nonzero(full > 0.5)
    slack = 1.0 / framing.scale + 1
    assert abs(xs.min() - x0) <= slack and abs(xs.max() + 1 - x1) <= slack
    assert abs(ys.min() - y0) <= slack and abs(ys.max() + 1 - y1) <= slack
    # and matches the alpha inside it
    a = alpha.astype(np.float32) / 255
    yy, xx = np.mgrid[0 : canvas_hw[0], 0 : canvas_hw[1]]
    cx_a, cy_a = (a * xx).sum() / a.sum(), (a * yy).sum() / a.sum()
    cx_s, cy_s = (full * xx).sum() / full.sum(), (full * yy).sum() / full.sum()
    assert abs(cx_a - cx_s) < 0.5 and abs(cy_a - cy_s) < 1.0
    assert np.abs(full - a).mean() < 0.02
    # the placed values are exactly the CanvasShadow's
    h, w = back.values.shape
    assert np.array_equal(full[back.y : back.y + h, back.x : back.x + w], back.values)


def test_shadow_to_canvas_is_clipped_to_the_canvas():
    alpha = np.zeros((100, 100), np.uint8)
    alpha[60:100, 40:60] = 255  # the object touches the canvas bottom
    _, framing = frame_alpha(alpha, 128)
    shadow = np.zeros((128, 128), np.float32)
    shadow[60:128, 20:108] = 0.5  # runs far below the object: off the canvas
    out = shadow_to_canvas(shadow, framing)
    assert out.y + out.values.shape[0] <= 100 and out.x + out.values.shape[1] <= 100
    assert out.x >= 0 and out.y >= 0
    assert out.values.max() <= 1.0


@pytest.mark.parametrize("canvas_hw", [(3000, 4000), (40, 60)])
@pytest.mark.parametrize("origin", [None, (-64.0, -40.0)])
def test_enlarged_shadow_is_the_bilinear_sample_at_each_canvas_pixel(canvas_hw, origin):
    """A canvas larger than the frame (the fast path) samples the frame bilinearly at canvas pixel centres,
    exactly as a plain bilinear resize of the padded frame would (a canvas smaller than the frame is that
    resize)."""
    h, w = canvas_hw
    alpha = _place((h // 2, w // 3), canvas_hw, (h // 4, w // 3), np.uint8)
    _, framing = frame_alpha(alpha, 128)
    rng = np.random.default_rng(3)
    n = 128 if origin is None else 256
    shadow = rng.random((n, n)).astype(np.float32)
    out = shadow_to_canvas(shadow, framing, origin)
    assert framing.scale < 1 or h < 128
    # the reference: every canvas pixel's centre mapped to the frame, interpolated between the four nearest
    # frame pixels (with zeros outside), after the same edge fade
    faded = fade_at_edges(shadow) if origin is None else shadow
    ox, oy = (0.0, 0.0) if origin is None else origin
    ys = (np.arange(out.y, out.y + out.values.shape[0]) + 0.5) * framing.scale + framing.offset_y - oy - 0.5
    xs = (np.arange(out.x, out.x + out.values.shape[1]) + 0.5) * framing.scale + framing.offset_x - ox - 0.5
    padded = np.pad(faded, 1)
    y0, x0 = np.floor(ys).astype(int), np.floor(xs).astype(int)
    fy, fx = (ys - y0)[:, None], (xs - x0)[None, :]
    y0, x0 = y0 + 1, x0 + 1

    def at(dy: int, dx: int) -> np.ndarray:
        return padded[np.clip(y0 + dy, 0, n + 1)[:, None], np.clip(x0 + dx, 0, n + 1)[None, :]]

    expected = (1 - fy) * ((1 - fx) * at(0, 0) + fx * at(0, 1)) + fy * ((1 - fx) * at(1, 0) + fx * at(1, 1))
    if h < 128:  # shrinking: antialiased, so only close to the point samples
        assert np.abs(out.values - expected).mean() < 0.2
    else:
        np.testing.assert_allclose(out.values, expected, atol=1e-4)


def test_shadow_to_canvas_empty_and_invisible_shadows():
    _, framing = frame_alpha(drawn_alpha(), 64)
    assert shadow_to_canvas(np.zeros((64, 64), np.float32), framing).is_empty
    faint = np.full((64, 64), 0.1 / 255, np.float32)
    assert shadow_to_canvas(faint, framing).is_empty
    empty = shadow_to_canvas(np.zeros((64, 64), np.float32), framing)
    assert not empty.full_canvas(160, 120).any()


def test_huge_canvas_frames_and_maps_back_within_memory():
    h, w = 8000, 12000
    alpha = np.zeros((h, w), np.uint8)
    yy, xx = np.ogrid[0:h, 0:w]
    alpha[1000:7000, 3000:9000] = 255
    alpha[((yy - 1500) ** 2 + (xx - 6000) ** 2) <= 1000**2] = 255  # not just a box
    tracemalloc.start()
    try:
        mask, framing = frame_alpha(alpha, 256)
        shadow = np.zeros((256, 256), np.float32)
        shadow[130:150, 40:220] = 0.8  # frame rows 130..150 are canvas rows ~6700..7700
        back = shadow_to_canvas(shadow, framing)
        _, peak = tracemalloc.get_traced_memory()
    finally:
        tracemalloc.stop()
    assert mask.shape == (256, 256)
    rows, cols = _visible_rows_cols(mask)
    assert rows[0] == top_row(256) and abs(cols[0] - (255 - cols[-1])) <= 1
    assert framing.bbox == (3000, 500, 9000, 7000)
    assert back.values.dtype == np.float32 and 0 < back.values.shape[0] <= h and 0 < back.values.shape[1] <= w
    assert back.y > framing.bbox[1]  # the ground shadow lies below the object's top
    assert peak < 3 * 2**30, f"peak traced memory {peak / 2**30:.2f} GiB"


def test_camera_input_follows_the_framing():
    """Conventions: h = k H + d and f = k F for the canvas horizon H and focal length F."""
    alpha = np.zeros((300, 400), np.uint8)
    alpha[100:200, 150:220] = 255
    _, framing = frame_alpha(alpha, 256)
    h, f = framing.camera_input(250.0, 50.0)
    assert h == pytest.approx(framing.to_frame(0.0, 250.0)[1])
    assert f == pytest.approx(framing.scale * 150.0 / np.tan(np.radians(25.0)))
    with pytest.raises(ValueError, match="field of view"):
        framing.camera_input(250.0, 0.0)


def test_a_frame_camera_maps_back_to_the_canvas():
    """``canvas_camera`` inverts ``camera_input``: the canvas horizon row and field of view come back."""
    alpha = np.zeros((300, 400), np.uint8)
    alpha[100:200, 150:220] = 255
    _, framing = frame_alpha(alpha, 256)
    for horizon, fov in ((250.0, 50.0), (-800.0, 30.0), (120.5, 75.0)):
        assert framing.canvas_camera(*framing.camera_input(horizon, fov)) == pytest.approx((horizon, fov))
