"""Several objects on one layer, each with its own frame, camera and shadow (ssn_engine.layer_session)."""

from __future__ import annotations

import numpy as np
import pytest
from engine_helpers import disc, pawn_scene, peak_alpha

from ssn_engine.ao_edit import AOEditError
from ssn_engine.framing import CanvasShadow
from ssn_engine.layer_session import LayerSession, combine_shadows, open_session
from ssn_engine.host_kit.light_map import preset
from ssn_engine.light_plan import LightPlan
from ssn_engine.methods import load_method
from ssn_engine.session import GIVEN_CAMERA_HEDGE, ShadowSession

W, H = 1400, 900
TWO = [(560, 820, 330), (300, 700, 1030)]  # (height, base row, centre column): a near pawn and a far one
THREE = [(500, 830, 260), (320, 720, 760), (200, 620, 1180)]
CAMERA = (420.0, 45.0)  # horizon row, field of view


@pytest.fixture(scope="module")
def method():
    return load_method("auto").method


@pytest.mark.parametrize("pawns", [TWO, THREE], ids=["two", "three"])
@pytest.mark.parametrize("camera", [CAMERA, (None, None)], ids=["camera", "blind"])
def test_each_object_casts_the_shadow_it_casts_alone(method, pawns, camera):
    """Each pawn's peak shadow alpha on the layer of them all is within 10 % of its peak alone with the same
    camera, under a low sun, a high sun and an overcast sky."""
    alphas = pawn_scene(W, H, pawns)
    session = open_session(np.maximum.reduce(alphas), method, *camera)
    assert isinstance(session, LayerSession) and len(session.parts) == len(pawns)
    blind = camera == (None, None)
    if blind:  # every object uses the camera read for the image
        read = session.camera_read
        assert read is not None
        camera = (read["horizon"], read["fov"])
    alone = [ShadowSession(alpha, method, *camera, read=blind) for alpha in alphas]
    for light in map(preset, ("low-sun-left", "high-sun", "overcast")):
        layer = session.render(light).full_canvas(W, H)
        for alpha, single in zip(alphas, alone, strict=True):
            own = single.render(light).full_canvas(W, H)
            region = (own > 2 / 255) & (alpha < 3)  # the pawn's own shadow on the ground it does not cover
            assert peak_alpha(own, region) > 0.1
            assert peak_alpha(layer, region) == pytest.approx(peak_alpha(own, region), rel=0.1)


def test_a_layer_of_one_object_is_the_single_session(method):
    (pawn,) = pawn_scene(W, H, [(560, 820, 600)])
    hand = disc(W, H, 760, 500, 20)  # a detached part stays with it: still one object
    for alpha in (pawn, np.maximum(pawn, hand)):
        session = open_session(alpha, method)
        assert type(session) is ShadowSession
        light = preset("low-sun-left")
        before = ShadowSession(alpha, method).render(light)
        after = session.render(light)
        assert (after.x, after.y) == (before.x, before.y) and np.array_equal(after.values, before.values)


def test_a_render_splits_its_light_map_once(method, monkeypatch):
    """One render, one plan: a layer of three objects under a sun and a sky splits the light map once and hands
    the plan to every object (its tracer, its network frames, the sum of the parts, the layer's combination)."""
    session = open_session(np.maximum.reduce(pawn_scene(W, H, THREE)), method, *CAMERA)
    made = []
    plan_of = LightPlan.of
    monkeypatch.setattr(
        LightPlan, "of", lambda light_map, lifted=0.0: made.append(light_map) or plan_of(light_map, lifted)
    )
    shadow = session.render(preset("sun")).full_canvas(W, H)
    assert shadow.max() > 0.5 and len(made) == 1


def test_one_camera_for_all_objects(method):
    """Blind, the largest object reads the camera and the others use it: one horizon on the canvas; and as a
    reading, not an artist's camera, so their traced lights keep the network's whole hedge."""
    alphas = pawn_scene(W, H, TWO)
    session = open_session(np.maximum.reduce(alphas), method)
    assert isinstance(session, LayerSession)
    main = ShadowSession(alphas[0], method)
    assert session.camera_read == main.camera_read
    assert [p.camera_read for p in session.parts] == [main.camera_read, None]  # the other is given it
    assert [p.hedge for p in session.parts] == [1.0, 1.0]
    given = open_session(np.maximum.reduce(alphas), method, *CAMERA)
    assert isinstance(given, LayerSession)
    assert given.camera_read is None and [p.hedge for p in given.parts] == [GIVEN_CAMERA_HEDGE] * 2


def test_a_camera_change_reaches_every_object(method):
    """set_camera on a layer: every object takes the given camera, with the AO edits kept; unset, the largest
    object reads it again and the others take its reading; the same as a layer opened with that camera."""
    alphas = pawn_scene(W, H, TWO)
    layer = np.maximum.reduce(alphas)
    session = open_session(layer, method)
    assert isinstance(session, LayerSession)
    read, edits = session.camera_read, [{"op": "strength", "value": 0.5}]
    session.set_ao_edits(edits)
    session.set_camera(*CAMERA)
    assert session.camera_read is None and all(p.cameras is not None for p in session.parts)
    assert all(p.hedge == GIVEN_CAMERA_HEDGE for p in session.parts)
    fresh = open_session(layer, method, *CAMERA)
    fresh.set_ao_edits(edits)
    np.testing.assert_allclose(session.ao, fresh.ao, atol=1e-6)
    light = preset("low-sun-left")
    np.testing.assert_allclose(session.render(light).values, fresh.render(light).values, atol=1e-6)
    session.set_camera()
    assert session.camera_read == read and all(p.hedge == 1.0 for p in session.parts)


def test_shadows_combine_as_light_does():
    a = CanvasShadow(np.full((2, 4), 0.6, np.float32), 10, 20)
    b = CanvasShadow(np.full((2, 4), 0.5, np.float32), 12, 20)  # overlaps a on columns 12 and 13
    hard = combine_shadows([a, b], 1.0)
    assert (hard.x, hard.y, hard.shape) == (10, 20, (2, 6))
    assert hard.values[0].tolist() == pytest.approx([0.6, 0.6, 0.6, 0.6, 0.5, 0.5])  # one small light: the darker
    broad = combine_shadows([a, b], 0.0)
    assert broad.values[0].tolist() == pytest.approx([0.6, 0.6, 0.8, 0.8, 0.5, 0.5])  # a sky: blocked parts add
    assert combine_shadows([a, b], 0.5).values[0, 2] == pytest.approx(0.7)
    assert combine_shadows([CanvasShadow(np.zeros((0, 0), np.float32), 0, 0)], 1.0).is_empty


def test_ao_edits_go_to_the_objects_they_touch(method):
    alphas = pawn_scene(W, H, TWO)
    session = open_session(np.maximum.reduce(alphas), method, *CAMERA)
    assert isinstance(session, LayerSession)
    big, small = session.parts
    before = [p.ao.copy() for p in session.parts]
    # a dab on the small pawn's base, placed on the layer's frame as a host places it
    x, y = session.framing.to_frame(1030, 700)
    n = session.framing.n
    ao = session.set_ao_edits([{"op": "brush", "x": x / n, "y": y / n, "radius": 0.03, "strength": -1.0}])
    assert ao.shape == (n, n) and ao[int(y), int(x)] < session.predicted_ao[int(y), int(x)] - 0.1
    assert np.array_equal(big.ao, before[0]) and big.edits == []
    assert len(small.edits) == 1 and small.ao.min() < before[1].min() + 1e-6
    sx, sy = small.framing.to_frame(1030, 700)  # the dab landed on the pawn's base in its own frame
    assert small.ao[int(sy), int(sx)] < before[1][int(sy), int(sx)] - 0.1
    session.set_ao_edits([{"op": "strength", "value": 0.0}])  # an edit without a place: every object
    assert all(np.all(p.ao == 1.0) for p in session.parts) and np.all(session.ao == 1.0)
    with pytest.raises(AOEditError, match=r"edits\[1\]\.radius"):
        session.set_ao_edits([{"op": "grow", "pixels": 2}, {"op": "brush", "x": 0.5, "y": 0.5, "radius": 3}])
    assert session.edits == [{"op": "strength", "value": 0.0}]  # a refused list changes nothing


def test_a_preview_of_a_smaller_canvas(method):
    alphas = pawn_scene(W, H, TWO)
    session = open_session(np.maximum.reduce(alphas), method, *CAMERA)
    assert isinstance(session, LayerSession)
    light = preset("low-sun-left")
    framing = session.framing.scaled(0.25)
    small = session.render(light, framing).full_canvas(framing.canvas_width, framing.canvas_height)
    full = session.render(light).full_canvas(W, H)
    shrunk = full[: H // 4 * 4, : W // 4 * 4].reshape(H // 4, 4, W // 4, 4).mean(axis=(1, 3))
    assert small.shape == shrunk.shape
    assert np.abs(small - shrunk).mean() < 0.01 and small.max() > 0.5
    cover = session.cover(framing)
    assert cover.shape == small.shape
    layer = np.maximum.reduce(alphas).astype(np.float32) / 255
    layer = layer[: H // 4 * 4, : W // 4 * 4].reshape(H // 4, 4, W // 4, 4).mean(axis=(1, 3))
    assert np.abs(cover - layer).mean() < 0.01


def test_a_method_that_reads_no_camera(geometric):
    """The geometric card reads no camera: each object assumes the default one in its own frame."""
    alphas = pawn_scene(W, H, TWO)
    session = open_session(np.maximum.reduce(alphas), geometric)
    assert isinstance(session, LayerSession) and session.camera_read is None
    light = preset("low-sun-left")
    layer = session.render(light).full_canvas(W, H)
    for alpha in alphas:
        alone = ShadowSession(alpha, geometric).render(light).full_canvas(W, H)
        region = (alone > 2 / 255) & (alpha < 3)
        assert peak_alpha(layer, region) == pytest.approx(peak_alpha(alone, region), rel=0.1)


def test_a_field_of_view_without_a_horizon_is_refused(method):
    with pytest.raises(ValueError, match="horizon"):
        open_session(np.maximum.reduce(pawn_scene(W, H, TWO)), method, None, 40.0)


def test_a_canvas_grown_by_a_margin_shows_the_same_shadows(method):
    """A layer clipped to the canvas grown by a margin (GIMP's layer) holds each object's shadow where the
    canvas's own holds it."""
    session = open_session(np.maximum.reduce(pawn_scene(W, H, TWO)), method, *CAMERA)
    assert isinstance(session, LayerSession)
    light, margin = preset("low-sun-left"), 60
    own = session.render(light).full_canvas(W, H)
    grown = session.render(light, session.framing.padded(margin))
    on_canvas = grown.full_canvas(W + 2 * margin, H + 2 * margin)[margin:-margin, margin:-margin]
    np.testing.assert_allclose(on_canvas, own, atol=0.02)
