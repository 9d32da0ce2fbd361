"""One cutout's shadow session (ssn_engine.session)."""

from __future__ import annotations

import numpy as np
import pytest
from engine_helpers import drawn_alpha, one_light

from ssn_engine import long_shadow
from ssn_engine.framing import EmptyAlphaError
from ssn_engine.host_kit.light_map import GaussianLight, LightMap, preset
from ssn_engine.light_plan import LightPlan
from ssn_engine.methods import GeometricCard
from ssn_engine.session import ShadowSession


class CountingMethod:
    """Wraps a method and counts its calls."""

    def __init__(self, inner):
        self.inner, self.name, self.resolution = inner, inner.name, inner.resolution
        self.ao_calls = self.render_calls = 0

    def predict_ao(self, masks, cameras=None):
        self.ao_calls += 1
        return self.inner.predict_ao(masks, cameras)

    def render(self, masks, ao, elms, cameras=None):
        self.render_calls += 1
        return self.inner.render(masks, ao, elms, cameras)


@pytest.fixture
def counting():
    return CountingMethod(GeometricCard(resolution=128))


def test_moving_a_light_reruns_only_render(counting):
    alpha = drawn_alpha(200, 150)
    session = ShadowSession(alpha, counting)
    assert counting.ao_calls == 1
    light = one_light(0.3, 0.6, softness=0.05)  # a broad light: the network's
    shadows = []
    for u in (0.3, 0.4, 0.6, 0.7):
        light.move(0, u, 0.6)
        shadows.append(session.render(light))
    session.set_ao_edits([{"op": "strength", "value": 0.5}])
    session.render(light)
    assert counting.ao_calls == 1
    assert counting.render_calls == 5
    # and the renders really follow the light: right of centre -> shadow left, and vice versa
    left = shadows[0].x + shadows[0].values.shape[1] / 2
    right = shadows[-1].x + shadows[-1].values.shape[1] / 2
    assert left > right


def test_a_small_light_is_traced_and_the_broad_light_rendered_in_one_network_pass(counting):
    session = ShadowSession(drawn_alpha(200, 150), counting)
    sun = LightMap([GaussianLight.disk(0.3, 0.6, 0.53, 2.0)])
    shadow = session.render(sun)
    assert counting.render_calls == 1 and shadow.values.max() > 0.99  # traced: fully dark in its umbra
    sky = LightMap([*sun.lights, GaussianLight(0.5, 0.1, 0.08, 1.0)])
    both = session.render(sky)
    assert counting.render_calls == 2  # the sun as a Gaussian and the broad light, in one pass
    # the sun's part is weighted by its share of the irradiance, so the mix is lighter than the sun alone
    assert 0.2 < both.values.max() < shadow.values.max()


def test_source_alpha_is_unchanged(counting):
    for alpha in (drawn_alpha(200, 150), drawn_alpha(200, 150, np.uint16), drawn_alpha(200, 150, np.float32)):
        before = alpha.copy()
        session = ShadowSession(alpha, counting)
        session.set_ao_edits([{"op": "brush", "x": 0.5, "y": 0.7, "radius": 0.1, "strength": -1}])
        session.render(preset("softbox"))
        assert np.array_equal(alpha, before)


def test_ao_edits_replace_the_list_and_keep_the_prediction(counting):
    session = ShadowSession(drawn_alpha(), counting)
    predicted = session.predicted_ao.copy()
    edited = session.set_ao_edits([{"op": "strength", "value": 0}])
    assert np.all(edited == 1.0) and np.all(session.ao == 1.0)
    assert np.array_equal(session.predicted_ao, predicted)
    restored = session.set_ao_edits([])  # undo: a shorter list
    assert np.array_equal(restored, predicted)
    assert session.edits == []


def test_bad_edit_keeps_the_previous_state(counting):
    session = ShadowSession(drawn_alpha(), counting)
    session.set_ao_edits([{"op": "strength", "value": 0.5}])
    ao = session.ao.copy()
    with pytest.raises(ValueError, match=r"edits\[0\]\.op"):
        session.set_ao_edits([{"op": "nope"}])
    assert np.array_equal(session.ao, ao) and session.edits == [{"op": "strength", "value": 0.5}]


def test_render_frame_and_canvas_shadow(counting):
    alpha = drawn_alpha(200, 150)
    session = ShadowSession(alpha, counting)
    broad = one_light(0.5, 0.7, 0.01)  # 36 degrees across: left to the network
    frames = session.render_frame(LightPlan.of(broad))  # the broad light's, and the small lights' (none)
    assert frames.shape == (2, 128, 128) and frames.dtype == np.float32
    assert frames[0].max() > 0.2 and frames[1].max() == 0
    shadow = session.render(broad)
    full = shadow.full_canvas(200, 150)
    ys, xs = np.nonzero(alpha > 127)
    assert full[ys.max() + 3 :].sum() > 0.8 * full[alpha < 128].sum()  # below the object: towards the viewer
    assert session.framing.bbox[2] <= 200


def test_empty_alpha(counting):
    with pytest.raises(EmptyAlphaError):
        ShadowSession(np.zeros((20, 20), np.uint8), counting)
    assert counting.ao_calls == 0


def test_a_long_shadow_continues_beyond_the_frame():
    """A low sun's shadow runs out of the network's frame; on the canvas it goes on, fading, never cut."""
    alpha = np.zeros((600, 1600), np.uint8)
    alpha[300:460, 700:820] = drawn_alpha(120, 160)
    session = ShadowSession(alpha, GeometricCard())
    frame_right = session.framing.to_canvas(256, 0)[0]  # the frame's right edge on the canvas
    sun = one_light(0.25, 0.92)  # left of the camera's forward direction, 7 degrees up: a long shadow to the right
    shadow = session.render(sun)
    full = shadow.full_canvas(1600, 600)
    cols = np.flatnonzero((full > 0.05).any(axis=0))
    assert cols.max() > frame_right + 50  # it reaches well past the frame
    # and fades out without a hard edge: no column-to-column jump anywhere along it
    profile = full.max(axis=0)
    assert np.abs(np.diff(profile[int(frame_right) - 40 : int(frame_right) + 40])).max() < 0.08
    # a high sun's short shadow stays inside the frame and is not extended
    short = session.render(one_light(0.25, 0.2)).full_canvas(1600, 600)
    assert np.flatnonzero((short > 0.02).any(axis=0)).max() < frame_right


def test_an_unclipped_shadow_reaches_past_the_canvas():
    """For hosts whose layers may extend past the canvas (GIMP): the same shadow, not cut at the canvas edge."""
    alpha = np.zeros((300, 400), np.uint8)
    alpha[100:260, 330:390] = drawn_alpha(60, 160)  # near the right edge
    session = ShadowSession(alpha, GeometricCard())
    sun = one_light(0.25, 0.92, 0.01)  # a long shadow to the right, of a broad light (the network's)
    plan = LightPlan.of(sun)
    frame = session.render_frame(plan)
    clipped, whole = session.to_canvas(frame, plan), session.to_canvas(frame, plan, clip=False)
    assert clipped.x + clipped.values.shape[1] <= 400  # cut at the canvas
    assert whole.x + whole.values.shape[1] > 450  # kept whole past it
    inside = whole.values[
        clipped.y - whole.y : clipped.y - whole.y + clipped.values.shape[0],
        clipped.x - whole.x : clipped.x - whole.x + clipped.values.shape[1],
    ]
    np.testing.assert_allclose(inside, clipped.values, atol=1e-5)  # the same shadow where both cover it


def test_a_small_and_a_broad_light_render_the_same_shadow_while_the_network_runs_beside_the_tracer():
    """``render`` runs the network on a thread of its own while the small lights are traced: the same pixels as
    the network's frames then the canvas, one after the other, for a sun with a sky, clipped or whole."""
    alpha = np.zeros((300, 400), np.uint8)
    alpha[100:260, 130:190] = drawn_alpha(60, 160)
    session = ShadowSession(alpha, GeometricCard())
    lights = LightMap([GaussianLight.disk(0.3, 0.7, 0.53, 1.0), GaussianLight(0.6, 0.3, 0.05, 0.5)])
    for clip in (True, False):
        together = session.render(lights, clip=clip)
        plan = LightPlan.of(lights)
        in_turn = session.to_canvas(session.render_frame(plan), plan, clip)
        assert (together.x, together.y) == (in_turn.x, in_turn.y)
        np.testing.assert_array_equal(together.values, in_turn.values)
        assert together.values.max() > 0.5


class BlanketMethod(CountingMethod):
    """The card's AO, and a network whose shadow of any light is 0.8 over the middle of its frame."""

    def render(self, masks, ao, elms, cameras=None):
        out = np.zeros(masks.shape, np.float32)
        n = masks.shape[-1]
        out[:, n // 4 : 3 * n // 4, n // 4 : 3 * n // 4] = 0.8
        return out


def test_a_given_camera_keeps_a_traced_sun_crisp_against_half_the_network_s_soft_shadow():
    """The network's soft shadow of a traced sun hedges against the traced geometry's errors: the traced shadow is
    kept no lighter than all of it when the model reads the camera, and than half of it when the camera is given
    (``GIVEN_CAMERA_HEDGE``); the traced umbra stays fully dark either way."""
    alpha = drawn_alpha(200, 150)
    sun = LightMap([GaussianLight.disk(0.3, 0.6, 0.53, 1.0)])
    method = BlanketMethod(GeometricCard(resolution=128))
    for session, hedge in ((ShadowSession(alpha, method), 1.0), (ShadowSession(alpha, method, 40.0, 45.0), 0.5)):
        values = session.render(sun).values
        assert values.max() > 0.99  # the traced umbra
        blanket = np.isclose(values, 0.8 * hedge, atol=0.01).mean()
        assert blanket > 0.1, (hedge, blanket)  # the network's shadow where the traced one is lighter
        assert np.isclose(values, 0.8 * (1.5 - hedge), atol=0.01).mean() < 0.01  # not the other's


def test_a_canvas_joins_only_the_part_of_a_long_shadow_it_sees():
    """The frame's shadow joined to the card's over a window (a clipped canvas's) is the whole join, cropped."""
    rng = np.random.default_rng(5)
    frame, wide = rng.random((64, 64)).astype(np.float32), rng.random((48, 48)).astype(np.float32)
    whole, (ox, oy) = long_shadow.extend(frame, wide)
    assert whole.shape == (192, 192) and (ox, oy) == (-64.0, -64.0)
    for window in [(-20.3, 10.0, 90.5, 70.2), (-64.0, -64.0, 128.0, 128.0), (70.0, -50.0, 100.0, -10.0)]:
        part, (px, py) = long_shadow.extend(frame, wide, window=window)
        x0, y0 = int(px - ox), int(py - oy)
        assert px <= window[0] and py <= window[1]
        assert px + part.shape[1] >= min(window[2], 128) and py + part.shape[0] >= min(window[3], 128)
        np.testing.assert_allclose(part, whole[y0 : y0 + part.shape[0], x0 : x0 + part.shape[1]], atol=1e-6)
    assert long_shadow.extend(frame, wide, window=(200.0, 0.0, 300.0, 50.0))[0].size == 0  # beyond its reach


def test_the_camera_read_from_the_outline_is_the_one_the_shadow_uses():
    """Blind, the shipped model reads a camera from the outline; reported on the canvas and given back, it is the
    same frame camera the blind session traced its card and long shadow with. The geometric card reads none."""
    from engine_helpers import REPO

    from ssn_engine.methods import OnnxSSN

    model = OnnxSSN(REPO / "ssn_engine" / "models")
    alpha = drawn_alpha()
    blind = ShadowSession(alpha, model)
    read = blind.camera_read
    assert read is not None
    given = ShadowSession(alpha, model, read["horizon"], read["fov"])
    assert given.camera_read is None
    np.testing.assert_allclose(given.used_cameras, blind.used_cameras, rtol=1e-6)
    assert ShadowSession(alpha, GeometricCard(resolution=128)).camera_read is None


def test_a_light_change_resolves_no_camera(monkeypatch):
    """The shipped model reads a blind cutout's camera from its mask: once, when the cutout (or its camera) is
    set, not on every light change (no estimator run, no digest of the mask); the render gets the camera read."""
    from pathlib import Path

    import ssn_engine
    from ssn_engine.methods import OnnxSSN
    from ssn_engine.methods import onnx_ssn

    model = OnnxSSN(Path(ssn_engine.__file__).parent / "models")
    if model._camera is None:
        pytest.skip("the shipped model has no camera estimator")
    calls = {"cameras_for": 0, "estimate": 0}
    cameras_for, estimate = model.cameras_for, onnx_ssn.estimate_cameras

    def counted_cameras_for(masks, cameras):
        calls["cameras_for"] += 1
        return cameras_for(masks, cameras)

    def counted_estimate(*args):
        calls["estimate"] += 1
        return estimate(*args)

    monkeypatch.setattr(model, "cameras_for", counted_cameras_for)
    monkeypatch.setattr(onnx_ssn, "estimate_cameras", counted_estimate)
    session = ShadowSession(drawn_alpha(200, 150), model)
    assert calls["estimate"] == 1 and session.used_cameras is not None
    calls.update(cameras_for=0, estimate=0)
    renders = []
    render = model.render
    monkeypatch.setattr(model, "render", lambda *args: renders.append(args[3]) or render(*args))
    for u in (0.3, 0.5, 0.7):
        session.render(one_light(u, 0.4, 0.01))
    assert calls == {"cameras_for": 0, "estimate": 0}
    assert all(np.array_equal(c, session.used_cameras) for c in renders)


def test_set_camera_analyses_again_and_keeps_the_ao_edits(counting):
    """A new camera predicts the AO again (on the kept frame) and re-applies the AO edits: the same AO as a new
    session with that camera and those edits."""
    alpha = drawn_alpha(200, 150)
    session = ShadowSession(alpha, counting)
    edits = [{"op": "strength", "value": 2.0}]
    session.set_ao_edits(edits)
    session.set_camera(40.0, 50.0)
    assert counting.ao_calls == 2
    fresh = ShadowSession(alpha, counting, 40.0, 50.0)
    fresh.set_ao_edits(edits)
    assert np.array_equal(session.ao, fresh.ao) and session.cameras is not None
    softbox = LightPlan.of(preset("softbox"))
    assert np.array_equal(session.render_frame(softbox), fresh.render_frame(softbox))
    session.set_camera(None)
    assert session.cameras is None and session.edits == edits


def test_a_faint_cutout_casts_a_faint_shadow():
    """A uniformly half-opaque cutout lets half the light through: about half the opaque one's shadow; one at 2 %
    2 % of it, no more (a layer shows it at most as 5 of 255)."""
    alpha = np.zeros((300, 400), np.uint8)
    alpha[60:260, 170:230] = 255
    sun = preset("low-sun-right")
    peaks = {}
    for value in (255, 128, 5):
        shadow = ShadowSession((alpha // 255 * value).astype(np.uint8), GeometricCard()).render(sun)
        peaks[value] = 0.0 if shadow.is_empty else float(shadow.values.max())
    assert peaks[255] > 0.9
    assert peaks[128] == pytest.approx(peaks[255] * 128 / 255, abs=0.05)
    assert peaks[5] == pytest.approx(peaks[255] * 5 / 255, abs=1 / 255)
