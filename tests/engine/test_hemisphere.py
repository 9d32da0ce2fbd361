"""The ELM texel grid and light maps rendered onto it (ssn_engine.hemisphere)."""

from __future__ import annotations

import numpy as np
import pytest
from engine_helpers import one_light
from scipy import integrate

from ssn_engine.hemisphere import (
    network_elm,
    render_light_map,
    soft_shadow,
    stratified_directions,
    texel_edges,
    texel_weights,
)
from ssn_engine.host_kit.light_map import LightMap
from ssn_engine.host_kit.sky_map import NETWORK_SHAPE


@pytest.mark.parametrize("h", [1, 4, 16, 64])
def test_texel_weights_sum_to_pi(h):
    w = texel_weights(h)
    assert w.shape == (h, 2 * h)
    assert np.all(w > 0)
    assert w.sum() == pytest.approx(np.pi, rel=1e-12)


@pytest.mark.parametrize("h", [4, 16])
def test_texel_weights_match_the_analytic_band_integral(h):
    w = texel_weights(h)
    for i in range(h):
        # row i: elevation 90 (1 - i/h) .. 90 (1 - (i+1)/h) degrees; cos(theta) = sin(elevation),
        # d omega = cos(elevation) de da. One column spans 2 pi / (2h) of azimuth.
        hi, lo = np.pi / 2 * (1 - i / h), np.pi / 2 * (1 - (i + 1) / h)
        band, _ = integrate.quad(lambda e: np.sin(e) * np.cos(e), lo, hi)
        assert w[i] == pytest.approx(np.full(2 * h, band * np.pi / h), rel=1e-9)
    # cosine-weighted: a texel at the zenith carries less than one at mid elevation
    assert w[0, 0] < w[h // 2, 0]


def test_texel_edges_follow_the_conventions():
    elevation, azimuth = texel_edges(16)
    assert elevation[0] == pytest.approx(np.pi / 2) and elevation[-1] == pytest.approx(0.0)
    assert np.all(np.diff(elevation) < 0)
    assert azimuth[0] == pytest.approx(-np.pi) and azimuth[-1] == pytest.approx(np.pi)
    assert azimuth[16] == pytest.approx(0.0)  # the centre column edge is straight ahead


@pytest.mark.parametrize("h, samples", [(4, 9), (16, 4)])
def test_stratified_directions_are_unit_above_horizon_and_inside_their_texel(h, samples):
    d = stratified_directions(h, samples, np.random.default_rng(0))
    assert d.shape == (h, 2 * h, samples, 3)
    assert np.allclose(np.linalg.norm(d, axis=-1), 1.0, atol=1e-9)
    assert np.all(d[..., 1] >= 0)
    elevation = np.arcsin(np.clip(d[..., 1], -1, 1))
    azimuth = np.arctan2(d[..., 0], d[..., 2])  # components: right, up, forward
    e_edges, a_edges = texel_edges(h)
    eps = 1e-9
    for i in range(h):
        assert np.all(elevation[i] <= e_edges[i] + eps) and np.all(elevation[i] >= e_edges[i + 1] - eps)
    for j in range(2 * h):
        a = azimuth[:, j]
        if j == 0 or j == 2 * h - 1:  # arctan2 may return +pi for -pi at the seam
            a = np.where(np.abs(a) > np.pi - 1e-9, np.sign(a_edges[j] + a_edges[j + 1]) * np.pi, a)
        assert np.all(a >= a_edges[j] - eps) and np.all(a <= a_edges[j + 1] + eps)


def test_stratified_directions_are_cosine_distributed():
    # Mean of sin^2(elevation) over a texel's samples is the middle of its sin^2 range
    # (uniform in sin^2 e = cosine-weighted), up to the jitter.
    h, k = 4, 64
    d = stratified_directions(h, k, np.random.default_rng(1))
    e_edges, _ = texel_edges(h)
    q = d[..., 1] ** 2
    mid = 0.5 * (np.sin(e_edges[:-1]) ** 2 + np.sin(e_edges[1:]) ** 2)
    assert np.allclose(q.mean(axis=(1, 2)), mid, atol=0.01)


def test_stratified_directions_need_a_square_count():
    with pytest.raises(ValueError, match="square"):
        stratified_directions(4, 5, np.random.default_rng(0))


def _energy(elm: np.ndarray) -> float:
    h = elm.shape[0]
    return float(elm.sum()) / h**2  # texel means times texel area (map heights^2)


@pytest.mark.parametrize("softness", [1e-4, 0.002, 0.02])
def test_render_light_map_conserves_energy_across_resolutions(softness):
    light = one_light(0.4, 0.5, softness, 2.0)
    expected = 2.0 * 2 * np.pi * softness  # the Gaussian's integral over the plane
    for h in (4, 8, 16, 64):
        elm = render_light_map(light, h)
        assert elm.shape == (h, 2 * h) and elm.dtype == np.float32
        assert np.all(elm >= 0)
        assert _energy(elm) == pytest.approx(expected, rel=1e-3)


def test_render_light_map_wraps_in_azimuth():
    at_edge = render_light_map(one_light(0.0, 0.5, 0.01, 1.0))
    centre = render_light_map(one_light(0.5, 0.5, 0.01, 1.0))
    # the light at u = 0 is split across the left and right edges, no energy lost
    assert _energy(at_edge) == pytest.approx(_energy(centre), rel=1e-4)
    assert at_edge[:, 0].sum() == pytest.approx(at_edge[:, -1].sum(), rel=1e-4)
    assert at_edge[:, 0].sum() > 10 * at_edge[:, 16].sum()
    # rolling by half the map turns one into the other
    assert np.allclose(np.roll(at_edge, 16, axis=1), centre, atol=1e-5)


def test_light_right_of_centre_lands_right_of_centre_column():
    elm = render_light_map(one_light(0.75, 0.5, 1e-3, 1.0))
    row, col = np.unravel_index(np.argmax(elm), elm.shape)
    assert col >= NETWORK_SHAPE[1] // 2 + 7  # 0.75 of the way across: the edge of columns 23 and 24
    assert elm[:, 23].sum() == pytest.approx(elm[:, 24].sum(), rel=1e-4)
    off = render_light_map(one_light(0.77, 0.53, 1e-3, 1.0))
    assert np.unravel_index(np.argmax(off), off.shape) == (8, int(0.77 * NETWORK_SHAPE[1]))
    # a zenith light lands on the top row
    top = render_light_map(one_light(0.3, 0.0, 1e-3, 1.0))
    assert np.argmax(top.max(axis=1)) == 0


def test_render_empty_light_map_is_zero():
    elm = render_light_map(LightMap())
    assert elm.shape == NETWORK_SHAPE and not elm.any()


def test_render_sums_lights():
    a, b = one_light(0.2, 0.3, 0.01, 1.0), one_light(0.7, 0.6, 0.005, 2.0)
    both = LightMap(a.lights + b.lights)
    assert np.allclose(render_light_map(both), render_light_map(a) + render_light_map(b), atol=1e-6)


def test_network_elm_peak_one_and_zero_stays_zero():
    rng = np.random.default_rng(0)
    elms = rng.random((3, 16, 32)).astype(np.float32) * np.array([5.0, 0.0, 0.01], np.float32)[:, None, None]
    out = network_elm(elms)
    assert out.dtype == np.float32 and out.shape == elms.shape
    assert out[0].max() == pytest.approx(1.0) and out[2].max() == pytest.approx(1.0)
    assert not out[1].any()
    assert np.allclose(out[0], elms[0] / elms[0].max())
    assert np.all(np.isfinite(out))


def _occlusion(rng, h=16, p=(5, 7)):
    return rng.random((h, 2 * h) + p)


def test_soft_shadow_zero_elm_gives_zero():
    occ = _occlusion(np.random.default_rng(0))
    s = soft_shadow(occ, np.zeros((16, 32)))
    assert s.shape == (5, 7) and not s.any()


def test_soft_shadow_is_intensity_scale_invariant():
    rng = np.random.default_rng(1)
    occ, elm = _occlusion(rng), render_light_map(one_light(0.3, 0.4, 0.01, 1.0))
    s = soft_shadow(occ, elm)
    assert np.allclose(soft_shadow(occ, 37.0 * elm), s, atol=1e-6)
    assert np.allclose(soft_shadow(occ, 1e-3 * elm), s, atol=1e-6)


def test_soft_shadow_is_linear_in_occlusion_and_a_weighted_mean_over_lights():
    rng = np.random.default_rng(2)
    o1, o2 = _occlusion(rng), _occlusion(rng)
    elm = render_light_map(one_light(0.6, 0.5, 0.02, 1.0))
    assert np.allclose(
        soft_shadow(0.3 * o1 + 0.5 * o2, elm), 0.3 * soft_shadow(o1, elm) + 0.5 * soft_shadow(o2, elm), atol=1e-6
    )
    # two ELMs: the shadow under their sum is the irradiance-weighted mean of the two shadows
    l1, l2 = render_light_map(one_light(0.2, 0.3, 0.01, 1.0)), render_light_map(one_light(0.8, 0.7, 0.01, 2.0))
    w = texel_weights(16)
    e1, e2 = float((l1 * w).sum()), float((l2 * w).sum())
    expected = (e1 * soft_shadow(o1, l1) + e2 * soft_shadow(o1, l2)) / (e1 + e2)
    assert np.allclose(soft_shadow(o1, l1 + l2), expected, atol=1e-5)


def test_soft_shadow_full_and_partial_occlusion():
    occ = np.zeros((16, 32, 2))
    elm = np.zeros((16, 32))
    elm[3, 20] = 1.0
    occ[3, 20, 0] = 1.0  # pixel 0 blocks the only lit texel
    occ[:, :, 1] = 1.0
    occ[3, 20, 1] = 0.0  # pixel 1 blocks everything but the lit texel
    assert np.allclose(soft_shadow(occ, elm), [1.0, 0.0])


def test_soft_shadow_shape_mismatch():
    with pytest.raises(ValueError, match="does not match"):
        soft_shadow(np.zeros((8, 16, 3)), np.ones((16, 32)))


@pytest.mark.parametrize("angle", [0.53, 3.0, 12.0, 25.0])
@pytest.mark.parametrize("v", [0.2, 0.55, 0.8])
def test_a_disk_light_rendered_into_the_map_keeps_its_power(angle, v):
    """The 16 x 32 map of a disk light holds the power of the reference Gaussian (conventions, "Light size")
    wherever it is and whatever its size: resizing a light does not make its shadow's share change."""
    from ssn_engine.host_kit.light_map import REFERENCE_SOFTNESS, GaussianLight, LightMap

    elevation, azimuth = texel_edges(16)
    solid_angle = (np.sin(elevation[:-1]) - np.sin(elevation[1:]))[:, None] * np.diff(azimuth)[None, :]
    disk = render_light_map(LightMap([GaussianLight.disk(0.3, v, angle, 2.0)]))
    gaussian = render_light_map(LightMap([GaussianLight(0.3, v, REFERENCE_SOFTNESS, 2.0)]))
    assert (disk * solid_angle).sum() == pytest.approx((gaussian * solid_angle).sum(), rel=0.02)
    # and it lies where the light is: the texel holding most of its power is the one of its centre or next to it
    if angle > 12.0:  # a large disk high up spans many azimuth texels
        return
    i, j = np.unravel_index(np.argmax(disk * solid_angle), disk.shape)
    assert abs(i - int(v * 16)) <= 1 and abs(j - int(0.3 * 32)) <= 1
