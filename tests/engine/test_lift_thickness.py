"""The artist's geometry (conventions, "Lift and thickness"): a lifted object's shadow detaches along the light and
softens with the height; a thickness makes a sign flat and a box deep; bad values are refused with what to give,
through the command line and the worker alike."""

from __future__ import annotations

import json
import re

import numpy as np
import pytest
from engine_helpers import converse, disc
from PIL import Image
from scipy import ndimage

from ssn_engine.camera import FORWARD, camera_for_span
from ssn_engine.cli import main
from ssn_engine.hard_light import ground_ahead, ground_rows, lowest_pixel, rigid_lifts
from ssn_engine.host_kit.light_map import GaussianLight, LightMap, preset
from ssn_engine.layer_session import LayerSession, open_session
from ssn_engine.methods import LoadedMethod, load_method
from ssn_engine.worker import Worker

W, H = 900, 700
CAMERA = (200.0, 45.0)  # horizon row, field of view
BALL = (450, 400, 80)  # centre column, centre row, radius: lowest row 479


@pytest.fixture(scope="module")
def method():
    return load_method("auto").method


def sun(elevation_v: float, angle: float = 0.53) -> LightMap:
    """A disk light in front of the camera, to the left (u 0.35), at map height ``elevation_v``."""
    return LightMap([GaussianLight.disk(0.35, elevation_v, angle, 1.0)])


def shadow_of(method, alpha: np.ndarray, light: LightMap, lift: float = 0.0, thickness: float | None = None):
    session = open_session(alpha, method, *CAMERA)
    session.set_geometry(lift, thickness)
    return session.render(light).full_canvas(W, H)


def top_row(shadow: np.ndarray, alpha: np.ndarray, level: float = 0.5) -> int:
    """The highest row where the shadow is at least ``level`` on ground the object does not cover."""
    rows = np.flatnonzero(((shadow >= level) & (alpha < 3)).any(axis=1))
    return int(rows[0])


@pytest.mark.parametrize("v", [0.3, 0.6], ids=["low sun", "high sun"])
def test_a_lifted_ball_casts_a_shadow_that_leaves_it_as_it_rises(method, v):
    ball = disc(W, H, *BALL)
    lowest = BALL[1] + BALL[2] - 1
    gaps = [top_row(shadow_of(method, ball, sun(v), lift), ball) - lowest for lift in (0, 40, 120)]
    assert gaps[0] <= 2  # resting: the shadow starts at the contact
    assert gaps[0] + 20 < gaps[1] < gaps[2] - 40, gaps


def test_a_lift_softens_a_small_lights_shadow(method):
    """The penumbra of a 3-degree light widens with the height: of the ground the shadow darkens, the share in
    its penumbra (0.1 to 0.9) grows as the ball rises (both heights past the network's share, all traced)."""
    ball = disc(W, H, *BALL)
    shares = []
    for lift in (30, 120):
        s = shadow_of(method, ball, sun(0.5, 3.0), lift)
        shares.append(((s > 0.1) & (s < 0.9)).sum() / (s > 0.1).sum())
    assert shares[1] > 1.2 * shares[0], shares


def test_a_lifted_object_loses_its_contact_blob(method):
    """Under an overcast sky a resting ball is darkest at its contact; lifted by a third of its height, the
    network's contact shadow is gone: the ground right below the ball is far lighter."""
    ball = disc(W, H, *BALL)
    below = (slice(BALL[1] + BALL[2], BALL[1] + BALL[2] + 12), slice(BALL[0] - 20, BALL[0] + 20))
    resting = shadow_of(method, ball, preset("overcast"))[below].mean()
    lifted = shadow_of(method, ball, preset("overcast"), 55.0)[below].mean()
    assert resting > 0.4 and lifted < 0.5 * resting


def test_a_thickness_makes_a_sign_flat_and_a_box_deep(method):
    """A rectangle's shadow under a sun from the side: 0 (a sign facing the camera) casts a line's worth, the
    reading about a round body's, 3 (a deep box) far more."""
    board = np.zeros((H, W), np.uint8)
    board[250:480, 380:520] = 255
    light = sun(0.45)
    areas = {t: int((shadow_of(method, board, light, 0.0, t) > 0.5).sum()) for t in (0.0, None, 3.0)}
    assert areas[0.0] < 0.6 * areas[None] and areas[3.0] > 1.5 * areas[None], areas


@pytest.mark.parametrize("thickness", [0.0, 0.05])
@pytest.mark.parametrize("lift", [0.0, 80.0], ids=["resting", "lifted"])
@pytest.mark.parametrize("v", [0.3, 0.75], ids=["high sun", "low sun"])
def test_a_thin_round_sign_casts_one_unbroken_shadow(method, lift, v, thickness):
    """A disc given (almost) no depth is (almost) a flat sign, one plane: its shadow is one piece under a high and
    a low sun, resting or lifted, not the strips of the cards its round bottom would stand on as a body (a
    ball's contact line rising at the sides stands them farther back)."""
    shadow = shadow_of(method, disc(W, H, *BALL), sun(v), lift, thickness)
    pieces, count = ndimage.label(shadow > 0.5)
    sizes = np.bincount(pieces.ravel())[1:]
    assert sizes.sum() > 500
    assert sizes.max() > 0.98 * sizes.sum(), sorted(sizes)[-5:]


@pytest.mark.parametrize("u, v", [(0.2, 0.55), (0.15, 0.6), (0.8, 0.55)])
def test_a_flat_sign_seen_from_above_casts_one_wedge_and_no_dotted_lines(method, u, v):
    """A board given thickness 0 is one plane, whatever depths the surface model reads across it: seen from above
    under a sun from the side its shadow is one thin wedge (s >= 0.5 in one piece). Before, its pixels stayed at
    the depths read (up to 44 pixels behind its card) with no depth to sweep between them, and the wedge's far
    part broke into 30 to 61 pieces, dotted lines (the sign of docs/img/lift_thickness.png)."""
    width, height = 900, 560
    board = np.zeros((height, width), np.uint8)
    board[190:370, 340:460] = 255
    session = open_session(board, method, 150.0, 40.0)
    session.set_geometry(0.0, 0.0)
    shadow = session.render(LightMap([GaussianLight.disk(u, v, 0.53, 1.0)])).full_canvas(width, height)
    pieces, count = ndimage.label(shadow >= 0.5)
    sizes = np.bincount(pieces.ravel())[1:]
    assert sizes.sum() > 1000
    assert count == 1, sorted(sizes)[-5:]


def test_a_lifted_object_is_as_deep_as_it_is_resting(method):
    """Floating changes where the object is, not its shape: the ball's thickness read (the surface model's depth
    reading over its width) is the same at every lift, and so is each of its pixels' depth behind its card."""
    session = open_session(disc(W, H, *BALL), method, *CAMERA)
    reads, depths = [], []
    for lift in (0.0, 60.0, 150.0):
        session.set_geometry(lift)
        reads.append(session.thickness_read)
        depths.append(np.concatenate([np.ravel(card.surface_depths[0]) for card in session.tracer.cards]))
    assert 0.8 < reads[0] < 1.1 and reads == [reads[0]] * 3, reads
    assert all(np.array_equal(d, depths[0]) for d in depths)


@pytest.mark.parametrize("horizon", [40.0, 120.0], ids=["looking down", "near eye level"])
@pytest.mark.parametrize("above", [0.0, 12.0], ids=["lowest pixel on the ground", "lowest pixel above it"])
def test_a_lifted_object_rises_as_one_body(horizon, above):
    """A floating object's feet move as the object scaled about the camera (the same image), so that the whole
    body rises by one world height: its lowest pixel's foot ends the lift below that pixel (where its surface stood
    ``above`` rows over the ground, by that much less), a foot farther back moves by fewer rows than a nearer one
    (a uniform shift in rows would lift the far part higher), every foot's ground point the same share nearer."""
    cam = camera_for_span(256, 30.0, 200.0, horizon, 300.0)[0]
    feet, lowest = np.array([150.0, 180.0, 200.0]), 200.0 - above  # the lowest pixel's surface stood on foot 200
    moved = rigid_lifts(cam, feet, lowest, 200.0, 40.0)
    assert feet[-1] + moved[-1] == pytest.approx(lowest + 40.0) and 0 < moved[0] < moved[1] < moved[2]
    here = float(cam.centre @ FORWARD)
    shares = (ground_ahead(cam, feet + moved) - here) / (ground_ahead(cam, feet) - here)
    np.testing.assert_allclose(shares, shares[-1], rtol=1e-9)
    np.testing.assert_allclose(ground_rows(cam, ground_ahead(cam, feet)), feet, atol=1e-9)


def test_no_geometry_and_lift_zero_are_the_same_shadow(method):
    ball = disc(W, H, *BALL)
    plain = open_session(ball, method, *CAMERA).render(preset("softbox")).full_canvas(W, H)
    np.testing.assert_array_equal(shadow_of(method, ball, preset("softbox"), 0.0, None), plain)


def test_a_dragged_lift_casts_what_a_fresh_one_does(method):
    """A lift dragged (each value after the last, the cutout's reading and the cards' blurred copies kept from one
    to the next) casts at every step the shadow the same lift and thickness cast in a session of their own."""
    ball = disc(W, H, *BALL)
    light = sun(0.45, 3.0)
    dragged = open_session(ball, method, *CAMERA)
    dragged.render(light)
    for lift, thickness in ((24.0, None), (40.0, None), (40.0, 0.5), (40.0, 0.0), (120.0, 0.5), (0.0, None)):
        dragged.set_geometry(lift, thickness)
        got = dragged.render(light).full_canvas(W, H)
        want = shadow_of(method, ball, light, lift, thickness)
        assert want.sum() > 500
        np.testing.assert_allclose(got, want, atol=2 / 255)


def test_a_lift_dragged_near_the_ground_runs_the_network_once_and_an_ao_edit_runs_it_again(method, monkeypatch):
    """Near the ground the network's shadow still hedges the traced one (fading as the ball rises). Dragged there
    under one light, each step casts what a fresh session casts, the network run once for them all; an AO edit
    between two steps is the network's input changed: it runs again and the shadow shows the edit."""
    ball = disc(W, H, *BALL)
    light = sun(0.45)
    lifts = (1.0, 2.0, 3.0, 5.0)
    fresh = [shadow_of(method, ball, light, lift) for lift in lifts]
    dragged = open_session(ball, method, *CAMERA)
    runs = []
    render = method.render
    monkeypatch.setattr(method, "render", lambda *args: runs.append(1) or render(*args))
    for lift, want in zip(lifts, fresh, strict=True):
        dragged.set_geometry(lift)
        assert 0.0 < dragged.lifted < 1.0  # the network's part still shows
        np.testing.assert_allclose(dragged.render(light).full_canvas(W, H), want, atol=2 / 255)
    assert len(runs) == 1, runs
    before = dragged.render(light).full_canvas(W, H)
    dragged.set_ao_edits([{"op": "brush", "x": 0.5, "y": 0.5, "radius": 0.5, "strength": -1.0}])
    after = dragged.render(light).full_canvas(W, H)
    assert len(runs) == 2
    assert np.abs(after - before).max() > 0.05


def test_every_object_of_a_layer_floats(method):
    alpha = np.maximum(disc(W, H, 250, 400, 70), disc(W, H, 650, 380, 60))
    session = open_session(alpha, method, *CAMERA)
    assert isinstance(session, LayerSession)
    session.set_geometry(60.0, 0.5)
    assert all(part.lift == 60.0 and part.thickness == 0.5 and part.lifted == 1.0 for part in session.parts)


@pytest.mark.parametrize(
    "lift, thickness, fragment",
    [
        (-1.0, None, "lift: expected 0 to"),
        (float("nan"), None, "lift: expected 0 to"),
        (1e9, None, "lift: expected 0 to"),
        ("high", None, "lift: expected 0 to"),
        (0.0, 9.0, "thickness: expected 0 to 8"),
        (0.0, float("inf"), "thickness: expected 0 to 8"),
    ],
)
def test_bad_geometry_is_refused_and_the_old_kept(method, lift, thickness, fragment):
    session = open_session(disc(W, H, *BALL), method, *CAMERA)
    session.set_geometry(30.0, 1.0)
    with pytest.raises(ValueError, match=fragment):
        session.set_geometry(lift, thickness)
    assert (session.lift, session.thickness) == (30.0, 1.0)


def test_a_lift_whose_ground_lies_above_the_horizon_is_refused(method):
    """A ball seen above the horizon (row 200) floats at least that high: its ground lies below the horizon."""
    ball = disc(W, H, 450, 120, 40)  # lowest row 159
    session = open_session(ball, method, *CAMERA)
    with pytest.raises(ValueError, match=r"lift: 10 puts the ground beneath the cutout at row 169, at or above"):
        session.set_geometry(10.0)
    session.set_geometry(60.0)
    assert session.lift == 60.0


def test_a_feathered_cutouts_lift_counts_from_its_lowest_pixel_not_from_its_feathers_last_row(method):
    """A ball above the horizon (row 200), its edge feathered 18 rows further down: its lift counts from its lowest
    pixel (conventions, "Lift and thickness"), so a lift whose ground lies at or above the horizon from there is
    refused, though the feather's last row plus that lift lies below it; the worker tells the hosts that row (their
    lift handle and their clamp count from it). Several objects: the highest's row, whose ground rises first."""
    ball = ndimage.gaussian_filter(disc(W, H, 450, 120, 40).astype(np.float32), 6.0).round().astype(np.uint8)
    last = int(np.flatnonzero(ball.any(axis=1))[-1])
    session = open_session(ball, method, *CAMERA)
    assert session.lift_row == lowest_pixel(ball / 255.0)[0] and last - session.lift_row >= 15
    lift = CAMERA[0] - session.lift_row - 2  # its ground 2 rows above the horizon; the feather's last row's below
    assert last + lift > CAMERA[0]
    with pytest.raises(ValueError, match=r"at or above the horizon \(row 200\)"):
        session.set_geometry(lift)
    session.set_geometry(CAMERA[0] - session.lift_row + 1)

    two = np.maximum(ball, disc(W, H, 200, 500, 60))
    layer = open_session(two, method, *CAMERA)
    assert isinstance(layer, LayerSession) and layer.lift_row == session.lift_row
    entry = {"name": "alpha", "dtype": "uint8", "shape": list(two.shape), "nbytes": two.size}
    header = {"id": 1, "cmd": "set_cutout", "camera": {"horizon": 200, "fov": 45}, "buffers": [entry]}
    reply = converse(Worker(LoadedMethod(method, "test")), json.dumps(header).encode() + b"\n" + two.tobytes())[0][0]
    assert reply["lift_row"] == session.lift_row and reply["bbox"][3] - 1 > reply["lift_row"] + 100


def test_a_camera_that_puts_a_lifted_objects_ground_above_the_horizon_is_refused_and_nothing_changes(method):
    session = open_session(disc(W, H, *BALL), method, *CAMERA)  # lowest row 479
    session.set_geometry(20.0)
    before = session.used_cameras.copy()
    with pytest.raises(ValueError, match="lift: 20 puts the ground beneath the cutout at row 499"):
        session.set_camera(600.0, 45.0)
    np.testing.assert_array_equal(session.used_cameras, before)
    session.set_geometry(0.0)
    session.set_camera(600.0, 45.0)  # resting: any horizon the model takes
    assert session.used_cameras[0, 0] != before[0, 0]


def _cutout_png(tmp_path, alpha: np.ndarray) -> str:
    rgba = np.zeros((*alpha.shape, 4), np.uint8)
    rgba[..., 3] = alpha
    Image.fromarray(rgba, "RGBA").save(tmp_path / "ball.png")
    return str(tmp_path / "ball.png")


def test_the_command_line_floats_the_ball_and_names_bad_values(tmp_path, capsys):
    cutout = _cutout_png(tmp_path, disc(W, H, *BALL))
    camera = ["--horizon", "200", "--fov", "45", "--preset", "high-sun"]
    layers = []
    for lift in ("0", "80"):
        out = tmp_path / f"lift{lift}.png"
        assert main(["render", cutout, *camera, "--lift", lift, "--layer", str(out)]) == 0
        layers.append(np.asarray(Image.open(out))[..., 3] / 255.0)
    printed = capsys.readouterr().out
    # a ball reads about round (1), lifted or not: the surface model's depth reading 0.89, the round cross-section
    # of a model without one 0.9 to 1.0
    reads = re.findall(r"thickness read from the cutout's outline: ([0-9.]+)", printed)
    assert reads and all(0.8 < float(read) < 1.1 for read in reads)
    ball = disc(W, H, *BALL)
    assert top_row(layers[1], ball) > top_row(layers[0], ball) + 40
    for bad, message in ((["--lift", "-2"], "expected a number >= 0"), (["--thickness", "20"], "[0, 8]")):
        out = tmp_path / "bad.png"
        with pytest.raises(SystemExit) as exit_:
            main(["render", cutout, *camera, *bad, "--layer", str(out)])
        assert exit_.value.code == 2 and message in capsys.readouterr().err and not out.exists()
    assert main(["render", cutout, "--horizon", "600", "--lift", "5", "--layer", str(tmp_path / "no.png")]) == 2
    assert "--lift: 5 puts the ground beneath the cutout at row 484" in capsys.readouterr().err
    assert not (tmp_path / "no.png").exists()


def test_the_worker_sets_the_geometry_without_the_alpha_and_stays_up(method):
    worker = Worker(LoadedMethod(method, "the shipped model"))
    alpha = disc(W, H, *BALL)
    entry = {"name": "alpha", "dtype": "uint8", "shape": list(alpha.shape), "nbytes": alpha.size}
    header = {"id": 1, "cmd": "set_cutout", "camera": {"horizon": 200}, "buffers": [entry]}
    replies, _ = converse(worker, json.dumps(header).encode() + b"\n" + alpha.tobytes())
    key = replies[0]["cutout"]

    def ask(i: int, **values) -> dict:
        request = {"id": i, "cmd": "set_geometry", "cutout": key, **values}
        return converse(worker, json.dumps(request).encode() + b"\n")[0][0]

    reply = ask(2, lift=70, thickness=0.5)
    assert reply["ok"] and reply["lift"] == 70 and reply["thickness"] == 0.5 and 0.8 < reply["thickness_read"] < 1.1
    bad = ask(3, lift=-4)
    assert not bad["ok"] and bad["error"]["type"] == "BadRequest" and "lift: expected 0 to" in bad["error"]["message"]
    assert ask(4)["lift"] == 0.0  # back on the ground: the worker answers after the refusal
