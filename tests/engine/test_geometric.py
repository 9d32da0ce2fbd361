"""The geometric card method (ssn_engine.methods.geometric) against the conventions' orientation."""

from __future__ import annotations

import numpy as np
import pytest
from engine_helpers import drawn_alpha, elm_for, object_geometry, shadow_centroid

from ssn_engine.ao_edit import apply_edits
from ssn_engine.camera import Camera
from ssn_engine.framing import frame_alpha
from ssn_engine.hemisphere import render_light_map, stratified_directions, texel_weights
from ssn_engine.host_kit.light_map import GaussianLight, LightMap
from ssn_engine.methods import GeometricCard
from ssn_engine.methods.geometric import AREA_SHARE


@pytest.fixture(scope="module")
def post_frame():
    mask, _ = frame_alpha(drawn_alpha(160, 120), 256)
    return mask


@pytest.fixture(params=["pawn", "post"])
def frame(request, pawn_frame, post_frame):
    return pawn_frame if request.param == "pawn" else post_frame


def _render(method, mask, elm, ao=None):
    if ao is None:
        ao = method.predict_ao(mask[None])
    return method.render(mask[None], ao if ao.ndim == 3 else ao[None], elm[None])[0]


@pytest.mark.parametrize("u", [0.6, 0.75, 0.9])
def test_light_right_of_centre_casts_the_shadow_left(geometric, frame, u):
    _, _, centre = object_geometry(frame)
    mass, cx, _ = shadow_centroid(_render(geometric, frame, elm_for(u, 0.6)), frame)
    assert mass > 10
    assert cx < centre - 5


@pytest.mark.parametrize("u", [0.1, 0.25, 0.4])
def test_light_left_of_centre_casts_the_shadow_right(geometric, frame, u):
    _, _, centre = object_geometry(frame)
    mass, cx, _ = shadow_centroid(_render(geometric, frame, elm_for(u, 0.6)), frame)
    assert mass > 10
    assert cx > centre + 5


def test_mirrored_lights_give_mirrored_shadow_masses(geometric, pawn_frame):
    _, _, centre = object_geometry(pawn_frame)
    _, left, _ = shadow_centroid(_render(geometric, pawn_frame, elm_for(0.7, 0.6)), pawn_frame)
    _, right, _ = shadow_centroid(_render(geometric, pawn_frame, elm_for(0.3, 0.6)), pawn_frame)
    assert (centre - left) == pytest.approx(right - centre, rel=0.1)


@pytest.mark.parametrize("v", [0.6, 0.8, 0.95])
def test_light_straight_ahead_casts_the_shadow_towards_the_viewer(geometric, frame, v):
    _, base, centre = object_geometry(frame)
    s = _render(geometric, frame, elm_for(0.5, v))
    mass, cx, cy = shadow_centroid(s, frame)
    assert mass > 10
    assert cy > base + 3  # below the object's base in the frame: in front of it
    assert abs(cx - centre) < 3
    assert s[base + 3 :].sum() > 0.9 * mass


@pytest.mark.parametrize("v", [0.3, 0.6, 0.9])
def test_shadow_touches_the_base(geometric, frame, v):
    """No lit seam between the object's base and the shadow it casts towards the viewer."""
    _, base, centre = object_geometry(frame)
    s = _render(geometric, frame, elm_for(0.5, v))
    c = int(centre)
    assert s[base + 4 : base + 9, c - 3 : c + 4].min() > 0.75


def test_lower_light_casts_a_longer_shadow(geometric, pawn_frame):
    reach = [shadow_centroid(_render(geometric, pawn_frame, elm_for(0.5, v)), pawn_frame)[2] for v in (0.2, 0.4, 0.6)]
    assert reach[0] + 3 < reach[1] < reach[2] - 3


@pytest.mark.parametrize("u", [0.0, 1.0, 0.02, 0.98])
def test_light_behind_the_camera_casts_the_shadow_behind_the_object(geometric, frame, u):
    _, base, _ = object_geometry(frame)
    s = _render(geometric, frame, elm_for(u, 0.6))
    mass, _, cy = shadow_centroid(s, frame)
    assert mass > 5
    assert cy < base  # above the base in the frame: behind the object
    assert s[base + 10 :].max() < 0.05  # nothing in front beyond the contact line


def test_u_0_and_u_1_are_the_same_light(geometric, pawn_frame):
    a = _render(geometric, pawn_frame, elm_for(0.0, 0.6))
    b = _render(geometric, pawn_frame, elm_for(1.0, 0.6))
    assert np.allclose(a, b, atol=1e-6)


@pytest.mark.parametrize(
    "lights", [[(0.3, 0.6, 0.002)], [(0.2, 0.5, 0.02), (0.8, 0.3, 0.05)], [(0.5, 0.2, 0.1), (0.1, 0.8, 0.1)]]
)
def test_the_card_shadow_is_the_light_weighted_mean_of_its_hard_shadows(pawn_frame, lights):
    """The weighted sum read over the texels a light uses equals the plain mean over every texel's shadow: along
    its centre direction, or over its area for a texel holding at least AREA_SHARE of the light."""
    card = GeometricCard(resolution=256).card(pawn_frame)
    elm = render_light_map(LightMap([GaussianLight(u, v, softness, 1.0) for u, v, softness in lights]))
    weights = elm.ravel() * texel_weights(16).ravel()
    card.trace()
    w = weights / weights.sum()
    bright = np.flatnonzero(w >= AREA_SHARE)
    assert (bright.size > 0) == (lights[0][2] < 0.01)  # a small light's texels are traced over their areas
    centre = w.copy()
    centre[bright] = 0.0
    expected = np.zeros(card.mask.shape, np.float32)
    expected[card.valid] = centre @ card.bases.astype(np.float64) + w[bright] @ card.area_bases(bright)
    np.testing.assert_allclose(card.shadow(weights), np.clip(expected, 0, 1), atol=2e-4)


def test_a_card_traced_as_lights_come_sums_the_shadows_of_one_traced_at_once(pawn_frame):
    """A card traces a texel's hard shadow when a light first needs it and sums each texel over the ground its
    shadow covers; a light moved over a half-traced card gives, to the bit, what the fully traced card gives."""
    lazy = GeometricCard(resolution=256).card(pawn_frame)
    full = GeometricCard(resolution=256).card(pawn_frame)
    full.trace()
    for lights in ([(0.3, 0.6, 0.002)], [(0.2, 0.5, 0.02), (0.8, 0.3, 0.05)], [(0.35, 0.55, 0.03)], [(0.5, 0.9, 0.1)]):
        elm = render_light_map(LightMap([GaussianLight(u, v, softness, 1.0) for u, v, softness in lights]))
        weights = elm.ravel() * texel_weights(16).ravel()
        shadow = lazy.shadow(weights)
        assert shadow.max() > 0.05 and np.array_equal(shadow, full.shadow(weights))
        if lights[0][2] < 0.01:  # a sun: only the few texels around it are traced so far
            assert 0 < lazy.traced.sum() < 0.1 * lazy.traced.size


def test_all_zero_elm_gives_no_shadow(geometric, frame):
    s = _render(geometric, frame, np.zeros((16, 32), np.float32))
    assert s.shape == (256, 256) and not s.any()


@pytest.mark.parametrize("k", [1e-3, 0.5, 40.0])
def test_scaling_the_elm_does_not_change_the_shadow(geometric, frame, k):
    elm = elm_for(0.4, 0.5) + 0.3 * elm_for(0.8, 0.3, 0.02)
    assert np.allclose(_render(geometric, frame, k * elm), _render(geometric, frame, elm), atol=1e-5)


def test_outputs_are_float32_in_unit_range_with_the_batch_shape(geometric, pawn_frame, post_frame):
    masks = np.stack([pawn_frame, post_frame, np.zeros_like(pawn_frame)])
    ao = geometric.predict_ao(masks)
    assert ao.shape == (3, 256, 256) and ao.dtype == np.float32
    assert 0.0 <= ao.min() and ao.max() <= 1.0
    elms = np.stack([elm_for(0.3, 0.7), 3.0 * elm_for(0.6, 0.2, 0.05), elm_for(0.5, 0.5)])
    s = geometric.render(masks, ao, elms)
    assert s.shape == (3, 256, 256) and s.dtype == np.float32
    assert 0.0 <= s.min() and s.max() <= 1.0
    assert s[0].max() > 0.3 and s[1].max() > 0.1
    assert not s[2].any()  # an empty mask casts nothing
    assert np.allclose(ao[2], 1.0)  # and occludes nothing


def test_ao_is_dark_at_contact_and_open_far_away(geometric, pawn_frame):
    ao = geometric.predict_ao(pawn_frame[None])[0]
    _, base, centre = object_geometry(pawn_frame)
    c = int(centre)
    # just in front of the base the ground is occluded like the foot of a wall (A ~ 0.5, AO ~ 0.8),
    # with no lit seam between the object and its contact shadow
    assert ao[base + 1 : base + 12, c].max() < 0.86
    assert ao[250, 5] > 0.97  # far corner of the ground
    assert ao[0, 0] == pytest.approx(1.0)  # above the horizon: AO 1


def test_darkening_the_ao_near_the_base_increases_the_shadow_there(geometric, pawn_frame):
    _, base, centre = object_geometry(pawn_frame)
    ao = geometric.predict_ao(pawn_frame[None])[0]
    elm = elm_for(0.3, 0.6)
    x, y, r = centre / 256, (base + 6) / 256, 0.06
    darker = apply_edits(ao, [{"op": "brush", "x": x, "y": y, "radius": r, "strength": -0.8}])
    plain = _render(geometric, pawn_frame, elm, ao)
    edited = _render(geometric, pawn_frame, elm, darker)
    region = np.zeros((256, 256), bool)
    yy, xx = np.mgrid[0:256, 0:256]
    region[((xx + 0.5 - x * 256) ** 2 + (yy + 0.5 - y * 256) ** 2) < (0.5 * r * 256) ** 2] = True
    assert np.all(edited >= plain - 1e-6)
    assert (edited - plain)[region].mean() > 0.2
    far = ((xx - x * 256) ** 2 + (yy - y * 256) ** 2) > (r * 256 + 2) ** 2
    assert np.allclose(edited[far], plain[far], atol=1e-6)  # nothing changes away from the brush


def test_an_open_ao_map_only_lightens_the_shadow(geometric, pawn_frame):
    """Removing all contact occlusion (AO = 1) lightens the shadow where the AO was dark."""
    elm = elm_for(0.62, 0.75)
    ao = geometric.predict_ao(pawn_frame[None])
    s = geometric.render(pawn_frame[None], ao, elm[None])[0]
    lit = 1.0 - np.clip(ao[0], 0, 1) ** 3  # the AO alone would make this much occlusion
    assert s.max() > 0.5
    assert np.all(s <= 1.0)
    # a fully open AO removes the contact darkening, so the shadow can only get lighter
    open_ao = np.ones_like(ao)
    lighter = geometric.render(pawn_frame[None], open_ao, elm[None])[0]
    assert np.all(lighter <= s + 1e-6)
    assert (s - lighter)[lit > 0.3].mean() > 0.05


def test_bad_shapes_name_the_argument(geometric, pawn_frame):
    with pytest.raises(ValueError, match="masks"):
        geometric.predict_ao(pawn_frame)
    with pytest.raises(ValueError, match="elms"):
        geometric.render(pawn_frame[None], pawn_frame[None], np.zeros((1, 8, 16), np.float32))
    with pytest.raises(ValueError, match="ao"):
        geometric.render(pawn_frame[None], pawn_frame[None, :128], np.zeros((1, 16, 32), np.float32))


def test_other_resolution(post_frame):
    method = GeometricCard(resolution=128)
    mask, _ = frame_alpha(drawn_alpha(160, 120), 128)
    s = _render(method, mask, elm_for(0.5, 0.8))
    _, base, _ = object_geometry(mask)
    assert s.shape == (128, 128)
    assert shadow_centroid(s, mask)[2] > base


def _area_lit(card, elm: np.ndarray, ground: np.ndarray | None = None) -> np.ndarray:
    """The card's exact shadow on its ground points (or on ``ground``) with every texel lit over its area (64
    directions each), for the texels holding all but 1e-4 of the light: (P,)."""
    dirs = Camera(card.mask.shape[0], 0.5).to_world(stratified_directions(16, 64)).reshape(512, 64, 3)
    w = elm.ravel() * texel_weights(16).ravel()
    lit = np.flatnonzero(w > 1e-4 * w.sum())
    return (w[lit] / w[lit].sum()) @ np.stack([card.occlusion(dirs[t], ground).mean(axis=0) for t in lit])


def _relative_rmse(got: np.ndarray, truth: np.ndarray) -> float:
    return float(np.sqrt(np.mean((got - truth) ** 2)) / np.sqrt(np.mean(truth**2)))


@pytest.mark.parametrize("u, v", [(0.25, 0.92), (0.7, 0.88), (0.4, 0.8)])
def test_a_small_lights_long_shadow_beyond_the_frame_is_smooth(geometric, pawn_frame, u, v):
    """Past the frame a texel holding much of a small light is traced over its area, not along one direction
    (which leaves a low sun's long shadow as separate streaks 11 degrees apart): close to the texels' exact
    area-lit shadows."""
    elm = elm_for(u, v)
    got = geometric.extended_shadow(pawn_frame, elm)
    card = geometric.card(pawn_frame)
    ground, valid = card.ground_grid(1.0, 4.0 * geometric.internal / 256)
    truth = np.zeros(valid.shape, np.float32)
    truth[valid] = _area_lit(card, elm, ground)
    assert _relative_rmse(got, truth) < 0.12


@pytest.mark.parametrize("u, v", [(0.25, 0.92), (0.4, 0.8), (0.55, 0.5), (0.3, 0.3)])
def test_a_small_lights_shadow_in_the_frame_is_smooth(geometric, pawn_frame, u, v):
    """In the frame a small light's bright texels cast the card's shadow from their areas: within 4 % of the texels'
    exact area-lit shadows (one direction a texel, the streaks, is 7 to 12 % off)."""
    elm = elm_for(u, v)
    card = geometric.card(pawn_frame)
    truth = np.zeros(card.mask.shape, np.float32)
    truth[card.valid] = _area_lit(card, elm)
    assert _relative_rmse(card.shadow(elm.ravel() * texel_weights(16).ravel()), truth) < 0.04
