"""Ground truth of training batches: the store's algebra at the network's resolution."""

from __future__ import annotations

import numpy as np
import pytest
from test_train_standin import FakeStore

from ssn_engine.frames import resample_frames
from ssn_engine.hemisphere import network_elm, texel_weights
from training.batches import (
    BatchSampler,
    CachedView,
    ViewCache,
    irradiance_to_shadow,
    load_view,
    make_batch,
    mirror,
    targets_for,
)
from training.elm import render_lights, sample_family, sample_lights
from training.frames import area_downsample


def test_area_downsample_is_a_block_mean():
    x = np.arange(16, dtype=np.float32).reshape(1, 4, 4)
    np.testing.assert_allclose(area_downsample(x, 2)[0], [[2.5, 4.5], [10.5, 12.5]])
    np.testing.assert_array_equal(area_downsample(x, 4), x)  # the same size: unchanged
    with pytest.raises(ValueError, match="multiple"):
        area_downsample(x, 3)


@pytest.mark.parametrize("factor", [2, 4])
def test_area_downsample_of_uint8_bases_is_exact(factor):
    """The bases are uint8: their block means come from exact integer sums, equal to the float mean."""
    occ = np.random.default_rng(0).integers(0, 256, (3, 8 * factor, 8 * factor), dtype=np.uint8)
    got = area_downsample(occ, 8)
    ref = occ.astype(np.float64).reshape(3, 8, factor, 8, factor).mean(axis=(2, 4))
    assert got.dtype == np.float32
    np.testing.assert_allclose(got, ref, rtol=0, atol=1e-5)


def test_shadow_target_is_the_downsampled_store_shadow():
    store = FakeStore(res=32)
    v16 = load_view(store, 0, 16)
    lights = sample_lights(np.random.default_rng(0), 3)
    elm = render_lights(lights, 4)
    got = targets_for(v16.occ, elm, np.ones(3), store._weights, "shadow").reshape(3, 16, 16)
    ref = np.stack([area_downsample(store.shadow(store.load(0).occlusion, e)[None], 16)[0] for e in elm])
    np.testing.assert_allclose(got, ref, atol=2.5 / 255)


def test_irradiance_target_and_conversion_back_to_shadow():
    store = FakeStore(res=16)
    v = load_view(store, 1, 16)
    lights = sample_lights(np.random.default_rng(1), 4)
    elm_hb, elm16 = render_lights(lights, 4), render_lights(lights, 16)
    peak = elm16.reshape(4, -1).max(axis=1)
    e = targets_for(v.occ, elm_hb, peak, store._weights, "irradiance")
    for b in range(4):
        np.testing.assert_allclose(
            e[b], store.irradiance(store.load(1).occlusion, elm_hb[b] / peak[b]).ravel(), rtol=1e-4, atol=1e-5
        )
    s = targets_for(v.occ, elm_hb, peak, store._weights, "shadow")
    np.testing.assert_allclose(irradiance_to_shadow(e, elm_hb, elm16), s, atol=1e-5)


def test_batch_shapes_inputs_and_elm_normalisation():
    store = FakeStore(res=32)
    cache = ViewCache(store, "train", 16, max_views=3)
    b = BatchSampler(cache, 6, "shadow", elms_per_view=2)(np.random.default_rng(0))
    assert b.mask.shape == b.ao.shape == b.target.shape == (6, 16, 16)
    assert b.elm.shape == (6, 16, 32)
    np.testing.assert_allclose(b.elm.reshape(6, -1).max(axis=1), 1.0)
    keys = {k: i for k, i in cache.keys.items()}
    np.testing.assert_allclose(b.mask[0], resample_frames(store.load(keys[b.keys[0]]).mask[None], 16)[0])
    assert 0 <= b.target.min() and b.target.max() <= 1
    assert np.allclose(network_elm(render_lights(b.lights, 16)), b.elm)


def test_cache_rotates_within_its_limit():
    store = FakeStore(res=16, n_meshes=6, views=3)
    cache = ViewCache(store, "train", 16, max_views=4)
    rng = np.random.default_rng(0)
    seen = set()
    for _ in range(20):
        cache.fill(rng, swap=1)
        assert len(cache.views) <= 4
        seen |= set(cache.views)
    assert len(seen) == len(cache.ids)


def test_balanced_kinds_are_drawn_equally_often():
    store = FakeStore(res=16, n_meshes=12, views=2)
    for v in store._views:  # train: one human mesh (2 views) against five object meshes (10 views)
        v.info["kind"] = "human" if v.info["mesh_id"] == "fake_00" else "object"
    rng = np.random.default_rng(0)

    def human_share(balance: bool) -> float:
        cache = ViewCache(store, "train", 16, with_occ=False, balance_kinds=balance)
        keys = list(cache.keys)
        drawn = cache.draw(rng, keys, 4000, replace=True)
        batch = BatchSampler(cache, 400, None, elms_per_view=1)(rng)
        assert (
            abs(
                np.mean([cache.kinds[k] == "human" for k in batch.keys])
                - np.mean([cache.kinds[k] == "human" for k in drawn])
            )
            < 0.1
        )  # the sampler draws the same way
        return float(np.mean([cache.kinds[k] == "human" for k in drawn]))

    assert abs(human_share(False) - 2 / 12) < 0.03
    assert abs(human_share(True) - 0.5) < 0.03


def test_aop_batches_skip_the_target():
    store = FakeStore(res=16)
    cache = ViewCache(store, "train", 16, with_occ=False)
    b = make_batch(
        [cache.get(next(iter(cache.keys)))] * 2, sample_lights(np.random.default_rng(0), 2), 4, cache.weights, None
    )
    assert b.target.shape == (2, 16, 16) and not b.target.any()


def _mirror_symmetric_view(res: int = 16, rows: int = 2) -> CachedView:
    """A view whose scene is its own mirror image: a symmetric mask, and the hard shadow of ELM column j a
    copy shifted by 2j - (W - 1) pixels (so column W - 1 - j casts the mirrored shadow)."""
    mask = np.zeros((res, res), np.float32)
    mask[3:9, res // 2 - 3 : res // 2 + 3] = 1.0
    occ = np.stack(
        [
            np.roll(mask, (1 + i, 2 * j - (2 * rows - 1)), (0, 1)) * (0.4 + 0.3 * i)
            for i in range(rows)
            for j in range(2 * rows)
        ]
    )
    return CachedView(("sym",), mask, 1.0 - 0.5 * mask, np.rint(occ * 255).astype(np.uint8).reshape(len(occ), -1))


def test_mirrored_sample_is_the_mirrored_scene_under_the_mirrored_light():
    view, rows = _mirror_symmetric_view(), 2
    weights = texel_weights(rows)
    lights = sample_lights(np.random.default_rng(3), 4)
    b = make_batch([view] * 4, lights, rows, weights, "shadow")
    assert not np.allclose(b.target, b.target[..., ::-1], atol=1e-3)  # the lights are not symmetric themselves
    which = np.array([True, False, True, False])
    m = mirror(b, which)
    direct = make_batch([view] * 4, m.lights, rows, weights, "shadow")
    np.testing.assert_allclose(m.target, direct.target, atol=1e-6)
    np.testing.assert_allclose(m.elm, direct.elm, atol=1e-6)
    np.testing.assert_array_equal(m.target[1], b.target[1])
    np.testing.assert_array_equal(m.mask[0], b.mask[0][:, ::-1])
    np.testing.assert_allclose(mirror(m, which).elm, b.elm)


def test_the_card_channel_is_the_engines_card_shadow():
    """What the geometry-guided SR learns from is what the engine feeds it: the card at R, default or true camera."""
    from ssn_engine.methods import GeometricCard
    from training.batches import camera_input, make_batch

    store = FakeStore(res=32)
    view = load_view(store, 0, 16, card=GeometricCard(internal=16))
    mask = store.load(0).mask
    engine = GeometricCard(internal=16)
    for family in ("table1", "sun"):  # a sun's bright texels are traced over their areas
        lights = sample_family(np.random.default_rng(3), 2, family)
        batch = make_batch([view, view], lights, 4, store._weights, "shadow", np.array([False, True]))
        elm16 = render_lights(lights, 16)
        blind = engine.card_shadows(mask[None], elm16[:1])[0]
        seen = engine.card_shadows(mask[None], elm16[1:], np.array([camera_input(store.info(0), 32)]))[0]
        np.testing.assert_allclose(batch.card[0], blind, atol=2 / 255)
        np.testing.assert_allclose(batch.card[1], seen, atol=2 / 255)
    assert np.abs(seen - engine.card_shadows(mask[None], elm16[1:])[0]).max() > 0.05  # the camera matters


def test_blind_cards_can_carry_the_camera_estimators_error():
    """--blind-camera-error: the blind card is traced with the true camera moved by Laplace noise of the given
    scales (a reading of the camera from the mask misses it so), inside the camera input's bounds."""
    from ssn_engine.methods import GeometricCard
    from ssn_engine.methods.base import camera_limits
    from training.batches import blind_camera, camera_input, make_batch

    store = FakeStore(res=32)
    info, n = store.info(0), 32
    truth = np.array(camera_input(info, n))
    assert blind_camera(info, n, None, np.random.default_rng(0)) is None  # the conventions' default camera
    rng = np.random.default_rng(1)
    drawn = np.array([blind_camera(info, n, (0.2, 0.1), rng) for _ in range(4000)])
    (h_lo, h_hi), (f_lo, f_hi) = camera_limits(n)
    assert np.all((drawn[:, 0] >= h_lo) & (drawn[:, 0] <= h_hi) & (drawn[:, 1] >= f_lo) & (drawn[:, 1] <= f_hi))
    # a Laplace variable of scale b has median |x| = b ln 2
    assert np.median(np.abs(drawn[:, 0] - truth[0])) / n == pytest.approx(0.2 * np.log(2), rel=0.1)
    assert np.median(np.abs(np.log(drawn[:, 1] / truth[1]))) == pytest.approx(0.1 * np.log(2), rel=0.1)

    view = load_view(
        store, 0, 16, card=GeometricCard(internal=16), camera_error=(0.2, 0.1), rng=np.random.default_rng(5)
    )
    camera = blind_camera(info, n, (0.2, 0.1), np.random.default_rng(5))
    lights = sample_lights(np.random.default_rng(3), 1)
    batch = make_batch([view], lights, 4, store._weights, "shadow", np.array([False]))
    elm16 = render_lights(lights, 16)
    engine = GeometricCard(internal=16)
    expected = engine.card_shadows(store.load(0).mask[None], elm16, np.array([camera]))[0]
    np.testing.assert_allclose(batch.card[0], expected, atol=2 / 255)
