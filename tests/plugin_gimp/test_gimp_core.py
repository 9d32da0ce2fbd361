"""The run logic (ssn_core) with a fake GIMP host: fake engines and the real engine worker."""

import sys

import numpy as np
import pytest
from ssn_core import (
    Cutout,
    ShadowError,
    ShadowLayerData,
    make_shadow,
    release,
    set_camera,
    set_geometry,
    settings_from_arguments,
    target_note,
    upload_cutout,
)
from ssn_pixels import plan_for_precision

from ssn_engine.host_kit import camera_rules
from ssn_engine.host_kit.client import Cancelled, EngineClient, EngineError, WorkerUnavailable
from ssn_engine.host_kit.protocol import Buffer
from ssn_engine.host_kit.shadow_notes import HIDDEN

W, H = 160, 120


def pawn_alpha(dtype="uint8") -> np.ndarray:
    a = np.zeros((H, W), dtype)
    a[20:100, 70:90] = np.iinfo(dtype).max if dtype.startswith("uint") else 1.0
    return a


class FakeHost:
    """Records every call so tests can check what happens inside the undo group."""

    def __init__(self, precision="u8-non-linear", alpha=None, no_cutout=False, hidden=None):
        self.plan = plan_for_precision(precision)
        alpha = pawn_alpha(self.plan.alpha_dtype) if alpha is None else alpha
        self.alpha, self.no_cutout, self.hidden, self.calls, self.layers = alpha, no_cutout, hidden, [], []

    def hidden_reason(self):
        return self.hidden

    def pixel_plan(self):
        self.calls.append("pixel_plan")
        return self.plan

    def source_name(self):
        return "Pawn"

    def read_cutout(self, plan):
        self.calls.append("read_cutout")
        if self.no_cutout:
            raise ShadowError("the selection is empty and the layer has no alpha")
        return Cutout(W, H, str(self.alpha.dtype), self.alpha.tobytes(), 'the layer "Pawn"')

    def undo_group_start(self):
        self.calls.append("undo_group_start")

    def undo_group_end(self):
        self.calls.append("undo_group_end")

    def add_shadow_layer(self, name, shadow, plan):
        self.calls.append("add_shadow_layer")
        self.layers.append((name, shadow, plan))
        return f"layer:{name}"


class FakeEngine:
    """Answers like the worker, with a fixed 10 x 5 layer, or fails on one command."""

    def __init__(self, fail_on=None, error=None, size=(10, 5), bad_layer=False):
        self.fail_on, self.error, self.size, self.bad_layer = fail_on, error, size, bad_layer
        self.requests = []
        self.running = True

    def request(self, cmd, buffers=None, timeout=None, **params):
        self.requests.append((cmd, params, buffers))
        if cmd == self.fail_on:
            if isinstance(self.error, (WorkerUnavailable, Cancelled)):
                self.running = False  # the client stops a worker it gave up on
            raise self.error
        if cmd == "set_cutout":
            return {"ok": True, "cutout": "c1", "bbox": [0, 0, 1, 1]}, {}
        if cmd == "render":
            w, h = self.size
            dtype = params["format"]["dtype"]
            shape = (h, w + (1 if self.bad_layer else 0), 4)
            data = np.full(shape, 0.5, dtype) if dtype.startswith("float") else np.full(shape, 7, dtype)
            reply = {"ok": True, "x": 3, "y": 4, "width": w, "height": h, **({} if w else {"no_shadow": HIDDEN})}
            return reply, ({"layer": Buffer(dtype, shape, data.tobytes())} if w else {})
        return {"ok": True}, {}


ARGS = {"light-map": "low-sun-right", "shadow-color": (0, 0, 0), "opacity": 1.0, "ao-strength": 1.0}


def test_one_layer_inside_one_undo_group():
    host, engine = FakeHost(), FakeEngine()
    assert make_shadow(host, engine, ARGS) == "layer:Shadow: Pawn"
    assert host.calls == ["pixel_plan", "read_cutout", "undo_group_start", "add_shadow_layer", "undo_group_end"]
    name, shadow, _ = host.layers[0]
    assert (shadow.x, shadow.y, shadow.width, shadow.height, shadow.dtype) == (3, 4, 10, 5, "uint8")
    cmds = [r[0] for r in engine.requests]
    assert cmds == ["set_cutout", "render", "release"]  # AO strength 1: no edit_ao; the cutout is freed
    assert engine.requests[1][1]["preset"] == "low-sun-right"
    assert engine.requests[0][2]["alpha"].shape == (H, W)


@pytest.mark.parametrize(
    "precision, dtype",
    [
        ("u16-linear", "uint16"),
        ("half-perceptual", "float16"),
        ("float-linear", "float32"),
        ("double-non-linear", "float32"),
    ],
)
def test_layer_dtype_follows_precision(precision, dtype):
    host, engine = FakeHost(precision), FakeEngine()
    make_shadow(host, engine, ARGS)
    assert engine.requests[1][1]["format"] == {"dtype": dtype, "channels": "rgba"}
    assert host.layers[0][1].dtype == dtype


def test_ao_strength_sends_an_edit():
    host, engine = FakeHost(), FakeEngine()
    make_shadow(host, engine, {**ARGS, "ao-strength": 0.25})
    assert engine.requests[1][:2] == ("edit_ao", {"cutout": "c1", "edits": [{"op": "strength", "value": 0.25}]})


@pytest.mark.parametrize(
    "engine, fragment",
    [
        (FakeEngine("set_cutout", EngineError("EmptyAlpha", "nothing selected")), "nothing selected"),
        (FakeEngine("render", EngineError("LightMapError", "lights[0].u: bad")), "lights[0].u"),
        (FakeEngine("set_cutout", WorkerUnavailable("could not start the shadow engine")), "could not start"),
        (FakeEngine("render", OSError("broken pipe")), "Lost contact"),
        (FakeEngine(size=(0, 0)), f"No visible shadow: {HIDDEN.split(' (')[0]}"),
        (FakeEngine(bad_layer=True), "malformed layer"),
    ],
)
def test_failures_leave_the_image_untouched(engine, fragment):
    host = FakeHost()
    with pytest.raises(ShadowError, match=fragment.replace("[", r"\[").replace("]", r"\]")):
        make_shadow(host, engine, ARGS)
    assert "undo_group_start" not in host.calls and not host.layers
    if any(r[0] == "set_cutout" for r in engine.requests) and engine.fail_on != "set_cutout":
        assert engine.requests[-1][0] == "release"


def test_a_cancel_leaves_the_image_untouched_and_starts_no_worker():
    """The user stops waiting for a frozen render (the client has stopped the worker): no layer, no error to show
    (the procedure answers Cancel), and no fresh worker started just to free the cutout the old one took along."""
    host, engine = FakeHost(), FakeEngine("render", Cancelled("render"))
    with pytest.raises(Cancelled):
        make_shadow(host, engine, ARGS)
    assert "undo_group_start" not in host.calls and not host.layers
    assert [r[0] for r in engine.requests] == ["set_cutout", "render"]


def test_no_cutout_and_blank_alpha_never_reach_the_engine():
    engine = FakeEngine()
    with pytest.raises(ShadowError, match="selection is empty"):
        make_shadow(FakeHost(no_cutout=True), engine, ARGS)
    with pytest.raises(ShadowError, match="fully transparent"):
        make_shadow(FakeHost(alpha=np.zeros((H, W), "uint8")), engine, ARGS)
    assert engine.requests == []


def test_a_hidden_source_is_refused_before_reading_pixels():
    host, engine = FakeHost(hidden='The layer "Pawn" is hidden'), FakeEngine()
    with pytest.raises(ShadowError, match="is hidden"):
        make_shadow(host, engine, ARGS)
    assert host.calls == [] and engine.requests == []


def test_bad_arguments_fail_before_reading_pixels():
    host = FakeHost()
    with pytest.raises(ShadowError, match="opacity"):
        make_shadow(host, FakeEngine(), {**ARGS, "opacity": 3.0})
    assert host.calls == []


def test_undo_group_closes_when_adding_the_layer_fails():
    class Broken(FakeHost):
        def add_shadow_layer(self, name, shadow, plan):
            raise RuntimeError("boom")

    host = Broken()
    with pytest.raises(RuntimeError):
        make_shadow(host, FakeEngine(), ARGS)
    assert host.calls[-2:] == ["undo_group_start", "undo_group_end"]


def test_a_lift_and_thickness_go_with_the_cutout():
    host, engine = FakeHost(), FakeEngine()
    make_shadow(host, engine, {**ARGS, "lift": 30.0, "thickness": 0.5})
    assert engine.requests[0][0] == "set_cutout"
    assert engine.requests[0][1] == {"lift": 30.0, "thickness": 0.5}
    make_shadow(host, engine := FakeEngine(), {**ARGS, "lift": 30.0, "thickness": -1.0})
    assert engine.requests[0][1] == {"lift": 30.0, "thickness": None}  # -1: read from the outline
    make_shadow(host, engine := FakeEngine(), ARGS)
    assert engine.requests[0][1] == {}  # resting, read: the engine's defaults, nothing sent


def test_a_bad_lift_in_a_script_is_refused_clearly_and_changes_nothing():
    """A script's lift past 20 canvas heights (the engine's range): refused before the engine is asked, with the
    range; one the engine refuses (its ground above the horizon) with the engine's words; no layer either way."""
    host, engine = FakeHost(), FakeEngine()
    with pytest.raises(ShadowError, match=r"lift: expected 0 to 2400 canvas pixels .* got 5000.0. Nothing was"):
        make_shadow(host, engine, {**ARGS, "lift": 5000.0})
    assert engine.requests == [] and "undo_group_start" not in host.calls and not host.layers
    refusal = EngineError("BadRequest", "lift: 5 puts the ground beneath the cutout at row 104, at or above the ")
    host = FakeHost()
    with pytest.raises(ShadowError, match="at or above the"):
        make_shadow(host, FakeEngine("set_cutout", refusal), {**ARGS, "lift": 5.0})
    assert "undo_group_start" not in host.calls and not host.layers


def test_the_preview_s_lift_handle():
    """Dragging in the preview below the cutout sets the lift: canvas rows = preview rows / scale, less the row the
    lift counts from (the cutout's lowest pixel's, the worker's ``lift_row``); the handle is a mark at the ground
    point, with a dotted line up to the cutout when lifted."""
    from ssn_preview import GROUND_MARK, draw_ground_mark, in_lift_handle, lift_from_preview

    bbox, row = [70, 20, 90, 100], 91  # the pawn, its edge feathered: its lift counts from row 91, not 99
    assert lift_from_preview(100, 0.5, row) == 109.0 and lift_from_preview(10, 0.5, row) == 0.0
    assert in_lift_handle(40, 60, 0.5, bbox, row) and in_lift_handle(40, 43, 0.5, bbox, row)
    assert not in_lift_handle(40, 30, 0.5, bbox, row) and not in_lift_handle(5, 60, 0.5, bbox, row)
    w, h = 80, 80
    rgb = draw_ground_mark(bytes(3 * w * h), (w, h), 0.5, bbox, row, 20.0)
    marked = np.all(np.frombuffer(rgb, np.uint8).reshape(h, w, 3) == GROUND_MARK, axis=-1)
    rows = np.nonzero(marked.any(axis=1))[0]
    ground = round((row + 20) * 0.5)  # the ground point's row on the thumbnail: a bar two rows deep
    assert rows.max() == ground + 1 and marked[ground, 40 - 8 : 40 + 9].all() and not marked[ground, 30]
    assert rows.min() == round(row * 0.5) + 3  # the dotted line up to the cutout's foot
    assert draw_ground_mark(bytes(3 * w * h), (w, h), 0.5, bbox, row, 999.0) != bytes(3 * w * h)  # the dotted line


def test_settings_from_arguments_defaults():
    st = settings_from_arguments({})
    assert st.light_map == "softbox" and st.opacity == 0.85 and st.ao_strength == 1.0


# -- with the real engine worker ---------------------------------------------------------------
@pytest.fixture(scope="module")
def real_engine():
    client = EngineClient(command=[sys.executable, "-m", "ssn_engine", "serve"], timeout=120)
    try:
        client.request("hello")
    except EngineError as exc:  # pragma: no cover - the worker is part of this project
        pytest.fail(f"engine worker unavailable: {exc}")
    yield client
    client.close()


@pytest.mark.parametrize("precision", ["u8-non-linear", "u16-linear", "half-linear", "float-perceptual"])
def test_real_worker_casts_the_shadow_away_from_the_light(real_engine, precision):
    host = FakeHost(precision)
    make_shadow(host, real_engine, {**ARGS, "light-map": "low-sun-right"})  # light right of centre
    _, shadow, plan = host.layers[0]
    assert isinstance(shadow, ShadowLayerData) and shadow.dtype == plan.layer_dtype
    a = np.frombuffer(shadow.data, shadow.dtype).reshape(shadow.height, shadow.width, 4)[..., 3].astype("f4")
    a /= 255 if plan.layer_dtype == "uint8" else 65535 if plan.layer_dtype == "uint16" else 1
    assert a.max() > 0.3
    ys, xs = np.nonzero(a > 0.2)
    assert shadow.x + xs.mean() < 80 - 5  # the pawn's centre is x = 80: the shadow falls left
    # the low sun's shadow runs past the canvas's left edge: the layer reaches past it by the margin only
    assert -round(0.1 * W) == shadow.x


def test_a_faint_cutout_casts_its_shape_as_faint_as_it_is(real_engine):
    """A cutout at alpha 5/255 (2 % opaque) lets 98 % of the light through: its shadow is the opaque cutout's, at
    2 % of its darkness (not refused, not broken)."""
    peaks = []
    for level in (255, 5):
        host = FakeHost(alpha=(pawn_alpha() // 255 * level).astype("uint8"))
        make_shadow(host, real_engine, ARGS)
        _, shadow, _ = host.layers[0]
        peaks.append(
            int(np.frombuffer(shadow.data, shadow.dtype).reshape(shadow.height, shadow.width, 4)[..., 3].max())
        )
    assert peaks[1] == pytest.approx(peaks[0] * 5 / 255, abs=1)


@pytest.mark.parametrize("precision", ["u8-non-linear", "u16-linear", "float-perceptual"])
def test_dialog_preview_from_the_real_worker(real_engine, precision):
    """The dialog's preview: the image's cutout is uploaded once at its size and the worker casts its shadow on
    a thumbnail through the cutout's framing scaled to it (any cutout depth, no 8-bit cut in Python); the cutout
    hides its own shadow, and a horizon setting draws the line at the thumbnail's scale (without one: the horizon
    the model read, dotted)."""
    from ssn_preview import PREVIEW_SIZE, Thumbnail, render_preview

    assert camera_rules.preview_size(1024, 512, PREVIEW_SIZE) == (384, 192, 0.375)
    assert camera_rules.preview_size(100, 50, PREVIEW_SIZE) == (100, 50, 1.0)
    host = FakeHost(precision)
    tw, th, scale = camera_rules.preview_size(W, H, W // 2)  # a thumbnail at half the image's size
    thumbnail = Thumbnail(tw, th, 4, bytes([230, 230, 230, 255]) * (tw * th))
    key, read = upload_cutout(real_engine, host.read_cutout(host.plan))
    assert read is not None and set(read) == {"horizon", "fov"}  # no horizon set: the model read one
    settings = settings_from_arguments({**ARGS, "light-map": "high-sun", "use-horizon": True, "horizon": 40.0})
    camera = settings.camera()
    assert camera is not None and scale == 0.5
    assert set_camera(real_engine, key, camera) is None  # the image's camera: nothing read
    horizon = camera_rules.scaled_camera(camera, scale)["horizon"]
    rgb, no_shadow = render_preview(real_engine, key, settings, thumbnail, horizon)
    image = np.frombuffer(rgb, np.uint8).reshape(th, tw, 3)
    assert not no_shadow and image.min() < 150
    opaque = np.zeros((th, tw), bool)
    opaque[11:49, 36:44] = True  # inside the pawn (rows 20-100, columns 70-90 of the image), at half the size
    opaque[20] = False  # the horizon row
    assert (image[opaque] == 230).all()  # hidden under the opaque cutout
    assert tuple(image[20, 0]) == (255, 140, 0)  # horizon 40 at scale 0.5
    # no horizon set: the one the model read, dotted blue
    blind = settings_from_arguments({**ARGS, "light-map": "high-sun"})
    assert set_camera(real_engine, key, blind.camera()) == read  # back to the model's reading
    blind_rgb = np.frombuffer(render_preview(real_engine, key, blind, thumbnail)[0], np.uint8).reshape(th, tw, 3)
    dotted = np.all(blind_rgb == (40, 170, 255), axis=-1)
    row = int(np.nonzero(dotted.any(axis=1))[0][0])
    assert abs(row - read["horizon"] * scale) <= 1 and dotted.sum() == (tw + 1) // 2  # one dotted row
    dark = settings_from_arguments({**ARGS, "light-map": '{"format": "ssn-shadow-elm", "version": 1, "lights": []}'})
    assert render_preview(real_engine, key, dark, thumbnail)[1]
    release(real_engine, key)


def test_real_worker_a_lift_moves_the_shadow_down(real_engine):
    """The engine's lift in the filter's terms: the shadow's topmost row lies lower with lift 40 than resting, and the
    dialog's set_geometry reply carries the thickness the outline reads as."""
    tops = {}
    for lift in (0.0, 40.0):
        host = FakeHost()
        make_shadow(
            host, real_engine, {**ARGS, "light-map": "high-sun", "use-horizon": True, "horizon": 10.0, "lift": lift}
        )
        _, shadow, _ = host.layers[0]
        a = np.frombuffer(shadow.data, shadow.dtype).reshape(shadow.height, shadow.width, 4)[..., 3]
        tops[lift] = shadow.y + int(np.nonzero((a > 25).any(axis=1))[0][0])
    assert tops[40.0] > tops[0.0] + 10, tops
    key, _ = upload_cutout(real_engine, FakeHost().read_cutout(FakeHost().plan))
    reply = set_geometry(real_engine, key, 12.0, None)
    assert reply["lift"] == 12.0 and 0 < reply["thickness_read"] < 8
    release(real_engine, key)


def test_the_preview_note_says_where_the_read_horizon_is():
    """The line under the preview names the dotted blue line only where the preview draws it: a horizon read
    above or below the image is said to lie there."""
    from ssn_engine.host_kit.camera_rules import camera_read_note

    assert "horizon at row 80 (dotted blue), 48° field of view" in camera_read_note({"horizon": 80.0, "fov": 48.0}, 300)
    assert "row -42 (above the image)" in camera_read_note({"horizon": -42.0, "fov": 48.0}, 300)
    assert "row 300 (below the image)" in camera_read_note({"horizon": 300.0, "fov": 48.0}, 300)
    assert "dotted blue" not in camera_read_note({"horizon": 1200.0, "fov": 35.0}, 300)


def test_the_target_note_names_what_is_cast():
    """Issue item a: with a selection left over the dialog said 'the layer "horse"' while read_cutout cast the
    selection; the note names the selection and its size, and how to cast the layer instead."""
    assert target_note("horse", None, None) == 'Casting the shadow of the layer "horse".'
    assert target_note("horse", "Shadow: horse", None) == (
        'Casting the shadow of the layer "horse", replacing "Shadow: horse".'
    )
    note = target_note("horse", "Shadow: horse", (120, 80))
    assert note.startswith('Casting the shadow of the selection (120 x 80 pixels) in "horse", replacing "Shadow:')
    assert 'layer "horse"' not in note and "Select > None" in note
