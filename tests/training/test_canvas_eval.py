"""The canvas-scale evaluation: disk lights, the canvas renderer, the test set's files, metrics and scoring."""

from __future__ import annotations

import json
import shutil
import sys
from dataclasses import replace
from pathlib import Path
from typing import Any, cast

import numpy as np
import pytest
from PIL import Image
from scipy import ndimage

from ssn_engine.framing import CanvasShadow
from ssn_engine.hemisphere import direction
from ssn_engine.host_kit.light_map import LightMap
from ssn_engine.hard_light import light_direction, lowest_pixel
from ssn_engine.methods import load_method
from ssn_engine.session import ShadowSession
from training.canvas_eval import cases, disk, metrics, oracle, render, score, sheet
from training.canvas_eval.render_set import group_scene, planned_groups, render_set, shadow_share, true_lift
from training.data import meshes, procedural, sources
from training.data.items import Item
from training.data.raycast import ray_hits

ROOT = Path(__file__).resolve().parents[2]
FIXTURE = ROOT / "tests" / "data" / "canvas_eval"


# -- disk lights ---------------------------------------------------------------------------------------------
@pytest.mark.parametrize("angle,samples", [(0.53, 16), (3.0, 64), (12.0, 256)])
def test_disk_directions_fill_the_cap_uniformly(angle, samples):
    dirs = disk.disk_directions(35.0, -60.0, angle, samples, np.random.default_rng(1))
    centre = direction(np.radians(35.0), np.radians(-60.0))
    off = np.degrees(np.arccos(np.clip(dirs @ centre, -1, 1)))
    assert dirs.shape == (samples, 3) and np.allclose(np.linalg.norm(dirs, axis=1), 1.0)
    assert off.max() <= angle / 2 + 1e-9
    # Uniform in solid angle: the inner cap of half the radius holds a quarter of the directions.
    inner = (off <= angle / 4).mean()
    assert abs(inner - 0.25) < 0.08
    assert np.degrees(np.arccos(np.clip(dirs.mean(axis=0) / np.linalg.norm(dirs.mean(axis=0)) @ centre, -1, 1))) < (
        0.05 * angle
    )


def test_disk_directions_refuse_bad_input():
    with pytest.raises(ValueError, match="square"):
        disk.disk_directions(30.0, 0.0, 3.0, 10)
    with pytest.raises(ValueError, match="positive"):
        disk.disk_directions(30.0, 0.0, 0.0, 16)


def test_light_file_reads_with_the_engine_reader_at_the_disk_position():
    data = disk.light_map_file(30.0, 90.0, 12.0)
    light = data["lights"][0]
    assert light["angle"] == 12.0
    assert light["u"] == pytest.approx(0.75) and light["v"] == pytest.approx(2 / 3)
    parsed = LightMap.from_dict(data)  # a reader that knows no angle uses the softness
    assert len(parsed) == 1 and parsed.lights[0].softness == pytest.approx((12 / 360) ** 2)
    assert disk.equivalent_softness(0.53) == disk.equivalent_softness(3.0)  # both below the reader's range


# -- the canvas renderer ---------------------------------------------------------------------------------------
def _box_on_ground() -> meshes.Mesh:
    return meshes.normalise(meshes.clean(procedural.box((0.4, 1.0, 0.3), (0.0, 0.5, 0.0))))


def test_canvas_camera_frames_the_object_and_reports_its_horizon():
    mesh = _box_on_ground()
    v = np.ascontiguousarray(meshes.yawed(mesh.vertices, 30.0))
    canvas = render.canvas_camera(v, 320, 240, 15.0)
    rows = canvas.camera.project(v)[:, 1]
    assert rows.min() == pytest.approx(round(render.TOP_SHARE * 240))
    assert np.ptp(rows) == pytest.approx(render.OBJECT_SHARE * 240)
    # The horizon: where a level ray from the camera lands on the canvas.
    far = canvas.camera.centre + 1e6 * np.array([0.0, 0.0, -1.0])
    assert canvas.camera.project(far)[1] == pytest.approx(canvas.horizon, abs=1e-3)
    assert canvas.fov == pytest.approx(np.degrees(2 * np.arctan(120 / canvas.focal)))


def test_disk_shadow_matches_brute_force_ray_casting():
    mesh = _box_on_ground()
    v = np.ascontiguousarray(meshes.yawed(mesh.vertices, 20.0))
    canvas = render.canvas_camera(v, 96, 72, 30.0)
    dirs = canvas.camera.to_world(disk.disk_directions(25.0, 40.0, 12.0, 64, np.random.default_rng(0)))
    s = render.disk_shadow(v, mesh.faces, meshes.topology(mesh), canvas, dirs)
    g, down = canvas.camera.ground_points()
    pix = np.argwhere(down[: canvas.height])[::7]
    o = np.repeat(g[pix[:, 0], pix[:, 1]][:, None], len(dirs), 1).reshape(-1, 3)
    hits = ray_hits(o, np.tile(dirs, (len(pix), 1)), v, mesh.faces).reshape(len(pix), len(dirs))
    expected = hits @ dirs[:, 1] / dirs[:, 1].sum()
    assert expected.max() > 0.9 and (expected > 0.05).sum() > 10  # the check sees umbra and penumbra
    assert np.abs(s[pix[:, 0], pix[:, 1]] - expected).max() < 1e-5


def test_a_bigger_disk_spreads_the_same_shadow():
    mesh = _box_on_ground()
    v = np.ascontiguousarray(mesh.vertices)
    canvas = render.canvas_camera(v, 128, 96, 15.0)
    topo = meshes.topology(mesh)
    shadows = [
        render.disk_shadow(v, mesh.faces, topo, canvas, canvas.camera.to_world(disk.disk_directions(30, 20, a, n)))
        for a, n in ((0.53, 16), (12.0, 256))
    ]
    ground = metrics.ground_region(render.canvas_mask(v, mesh.faces, topo, canvas), canvas.horizon)
    sharp, soft = (metrics.gradient_energy(x, ground) for x in shadows)
    assert soft < 0.6 * sharp
    assert abs(shadows[0].sum() - shadows[1].sum()) < 0.1 * shadows[0].sum()


# -- the test set ----------------------------------------------------------------------------------------------
def _item(uid: str, kind: str, category: str, split: str = "test") -> Item:
    return Item(uid, split, kind, category, "mesh")


def test_pick_shapes_prefers_distinct_categories_then_fills_each_kind():
    items = [_item(f"a{i}", "animal", "horse") for i in range(4)] + [
        _item("g", "animal", "goat"),
        _item("b1", "object", "box"),
        _item("b2", "object", "box"),
        _item("c", "object", "can"),
        _item("t", "object", "can", split="train"),
    ]
    picked = cases.pick_shapes(items, {"animal": 2, "object": 2})
    kinds = sorted((it.kind, it.category) for it in picked)
    assert kinds == [("animal", "goat"), ("animal", "horse"), ("object", "box"), ("object", "can")]
    assert all(it.split == "test" for it in picked)


def test_a_validation_set_picks_the_validation_shapes_alone():
    """``render --split val``: a set to choose models by, of shapes the test set never shows."""
    items = [_item("t1", "object", "box"), _item("v1", "object", "box", "val"), _item("v2", "animal", "cat", "val")]
    picked = cases.pick_shapes(items, {"animal": 1, "object": 1}, split="val")
    assert sorted(it.id for it in picked) == ["v1", "v2"]
    assert [it.id for it in cases.pick_shapes(items, {"animal": 1, "object": 1})] == ["t1"]


def test_groups_cycle_the_pitches_and_keep_lights_in_range():
    items = [_item(f"s{i}", "object", f"c{i}") for i in range(3)]
    groups = cases.make_groups(items, 2, 1024, 768)
    assert [g.pitch for g in groups] == [0.0, 15.0, 30.0, 0.0, 15.0, 30.0]
    assert all(10 <= g.elevation <= 70 and -180 <= g.azimuth <= 180 for g in groups)
    assert groups == cases.make_groups(items, 2, 1024, 768)  # reproducible


def test_truth_and_cutout_round_trip(tmp_path):
    group = cases.make_groups([_item("s", "object", "c")], 1, 8, 6)[0]
    s = np.linspace(0, 1, 48, dtype=np.float32).reshape(6, 8)
    mask = (s > 0.5).astype(np.float32)
    cases.write_truth(tmp_path, group, 3.0, s)
    cases.write_cutout(tmp_path, group, mask)
    assert np.abs(cases.read_truth(tmp_path, group, 3.0) - s).max() <= 0.5 / cases.S_SCALE
    assert np.array_equal(cases.read_mask(tmp_path, group), mask)
    assert json.loads(cases.light_path(tmp_path, group, 3.0).read_text())["lights"][0]["angle"] == 3.0


def test_render_set_resumes_and_refuses_another_plan(tmp_path):
    if not (meshes.SHARED_MESHES / "manifest.csv").exists():
        pytest.skip("shared meshes not available")
    logs: list[str] = []
    groups = render_set(tmp_path, 64, 48, shapes=1, lights=1, log=logs.append)
    assert len(groups) == 1 and np.isfinite(groups[0].horizon)
    for angle in cases.ANGLES:
        assert cases.read_truth(tmp_path, groups[0], angle).shape == (48, 64)
    cases.truth_path(tmp_path, groups[0], 3.0).unlink()
    logs.clear()
    render_set(tmp_path, 64, 48, shapes=1, lights=1, log=logs.append)
    assert sum(" deg: " in line for line in logs) == 1  # only the missing truth was rendered again
    with pytest.raises(ValueError, match="other settings"):
        render_set(tmp_path, 64, 48, shapes=1, lights=2)


def test_a_floating_set_lifts_each_shape_and_scores_it_with_its_lift(tmp_path):
    if not (meshes.SHARED_MESHES / "manifest.csv").exists():
        pytest.skip("shared meshes not available")
    (group,) = render_set(tmp_path, 128, 96, shapes=1, lights=1, log=lambda _: None, floating=True)
    assert cases.LIFTS[0] <= group.lift_share <= cases.LIFTS[1] and group.lift > 5
    assert group.angles == cases.FLOATING_ANGLES
    assert all(cases.truth_path(tmp_path, group, a).is_file() for a in cases.FLOATING_ANGLES)
    assert not cases.truth_path(tmp_path, group, cases.ANGLES[-1]).is_file()
    standing = render_set(tmp_path / "standing", 128, 96, shapes=1, lights=1, log=lambda _: None)[0]
    floating, resting = cases.read_truth(tmp_path, group, 3.0), cases.read_truth(tmp_path / "standing", standing, 3.0)
    assert np.abs(floating - resting).max() > 0.5  # the same shape, camera and light: its shadow moved
    cmd = score.cli_command("py", tmp_path, group, 0.53, "camera", tmp_path / "l.png")
    assert cmd[cmd.index("--lift") + 1] == f"{group.lift:.2f}"
    assert "--lift" not in score.cli_command("py", tmp_path, group, 0.53, "blind", tmp_path / "l.png")


@pytest.mark.parametrize("elevation,azimuth,on_canvas", [(60.0, 180.0, True), (10.0, 0.0, False), (20.0, 90.0, False)])
def test_a_floating_case_s_light_is_checked_against_where_the_truth_s_shadow_falls(elevation, azimuth, on_canvas):
    """A box floating its height above the ground at eye level: a light from behind the viewer casts its shadow
    on the canvas; a low one from the front or the side throws it off, where the truth's shadow is empty."""
    mesh = _box_on_ground()
    v = np.ascontiguousarray(meshes.yawed(mesh.vertices, 0.0))
    v[:, 1] += 1.0
    canvas = render.canvas_camera(v, 320, 240, 0.0)
    dirs = canvas.camera.to_world(disk.disk_directions(elevation, azimuth, 0.53, 16))
    truth = render.disk_shadow(v, mesh.faces, meshes.topology(mesh), canvas, dirs)
    assert (shadow_share(v, canvas, elevation, azimuth) >= cases.SHADOW_ON_CANVAS) == on_canvas
    assert ((truth >= 0.5).sum() > 100) == on_canvas


def test_a_floating_plan_draws_another_light_where_the_drawn_one_throws_the_shadow_off_the_canvas():
    if not (meshes.SHARED_MESHES / "manifest.csv").exists():
        pytest.skip("shared meshes not available")
    planned = planned_groups(1024, 768, None, 2, 0, floating=True)
    drawn = cases.make_groups(cases.pick_shapes(sources.manifest_items()), 2, 1024, 768, floating=True)
    moved = [(a, b) for a, b in zip(drawn, planned, strict=True) if a != b]
    assert 0 < len(moved) < len(planned) / 2  # a few, not most
    for a, b in moved:  # only the light changed
        assert replace(a, elevation=b.elevation, azimuth=b.azimuth) == b
    for g in planned:
        v, _, _, canvas = group_scene(g)
        assert shadow_share(v, canvas, g.elevation, g.azimuth) >= cases.SHADOW_ON_CANVAS
    assert planned_groups(1024, 768, None, 2, 0) == cases.make_groups(
        cases.pick_shapes(sources.manifest_items()), 2, 1024, 768
    )  # resting cases as drawn


def test_a_floating_box_s_lift_is_counted_from_its_lowest_pixel():
    """The conventions' lift: from the cutout's lowest pixel (the box's front bottom edge, seen from above) down
    to the image of the ground beneath the surface seen there, not from the image of some lowest vertex (its
    back bottom corners lie as low, farther away, and rise by fewer rows)."""
    mesh = _box_on_ground()
    v = np.ascontiguousarray(meshes.yawed(mesh.vertices, 0.0))
    v[:, 1] += 0.5  # floating half its height above the ground
    canvas = render.canvas_camera(v, 320, 240, 30.0)
    alpha = render.canvas_mask(v, mesh.faces, meshes.topology(mesh), canvas)
    row, col = lowest_pixel(alpha)
    cam = canvas.camera
    ray = cam.rays(col + 0.5, row + 0.5)
    front = cam.centre + (v[:, 2].max() - cam.centre[2]) / ray[2] * ray  # where the ray meets the front face
    assert front[1] == pytest.approx(v[:, 1].min(), abs=0.01)  # the pixel shows the front face's bottom edge
    expected = cam.project(front * np.array([1.0, 0.0, 1.0]))[1] - (row + 0.5)
    lift = true_lift(v, mesh.faces, canvas, alpha)
    assert lift == pytest.approx(expected, abs=0.05)
    back = v[np.argmin(v[:, 2] + 10 * v[:, 1])]  # a back bottom corner
    back_lift = float(np.diff(cam.project(np.array([back, back * np.array([1.0, 0.0, 1.0])]))[:, 1])[0])
    assert lift > back_lift + 1.0


def test_fixture_is_a_readable_test_set():
    groups = cases.read_groups(FIXTURE)
    assert len(groups) >= 2
    for group in groups:
        mask = cases.read_mask(FIXTURE, group)
        region = metrics.ground_region(mask, group.horizon)
        for angle in cases.ANGLES:
            truth = cases.read_truth(FIXTURE, group, angle)
            assert truth.shape == mask.shape == (group.height, group.width)
            assert truth[region].max() > 0.5  # each case casts a visible shadow


# -- metrics ---------------------------------------------------------------------------------------------------
def _scene(n: int = 96) -> tuple[np.ndarray, np.ndarray, float]:
    """A hard-edged shadow strip below a square object, the horizon at row 10."""
    mask = np.zeros((n, n), np.float32)
    mask[20:50, 40:56] = 1.0
    truth = np.zeros((n, n))
    truth[50:80, 36:60] = 1.0
    truth[50:80, 60:70] = 0.4
    return mask, truth, 10.0


def test_ground_region_leaves_out_the_sky_and_the_dilated_object():
    mask, _, horizon = _scene()
    region = metrics.ground_region(mask, horizon)
    assert not region[:10].any() and region[10:].any()
    assert not region[19:51, 39:57].any() and region[18, 39] and region[51, 38]


def test_metrics_of_the_truth_itself_are_perfect():
    mask, truth, horizon = _scene()
    m = metrics.score_case(truth, truth, mask, horizon)
    assert m["zncc"] == pytest.approx(1.0) and m["bandpass_zncc"] == pytest.approx(1.0)
    assert m["dssim"] == pytest.approx(0.0, abs=1e-9)
    for name in ("gradient_energy", "dark_ratio", "contact_ratio", "iou"):
        assert m[name] == pytest.approx(1.0)
    assert m["outline_distance"] == 0.0
    assert np.isnan(m["gap_ratio"])  # the shadow touches the object: nothing floats


def test_iou_and_gap_see_a_shadow_in_the_wrong_place():
    """A floating object's shadow 10 rows below it: the truth's gap; a prediction glued to the object has
    none, one twice as far twice the gap, and its IoU with the truth falls."""
    mask, _, horizon = _scene()
    truth = np.zeros((96, 96))
    truth[60:80, 36:60] = 1.0  # 10 rows below the object's lowest row 49
    glued, far = np.zeros_like(truth), np.zeros_like(truth)
    glued[50:70, 36:60] = 1.0
    far[70:90, 36:60] = 1.0
    assert metrics.score_case(truth, truth, mask, horizon)["gap_ratio"] == pytest.approx(1.0)
    on, off = (metrics.score_case(p, truth, mask, horizon) for p in (glued, far))
    assert on["gap_ratio"] < 0.2 and off["gap_ratio"] == pytest.approx(2.0, rel=0.1)
    assert on["iou"] == pytest.approx(1 / 3, abs=0.02) and off["iou"] == pytest.approx(1 / 3, abs=0.02)
    # the outlines: the same shadow's lie on each other; shifted 10 rows, the top and bottom edges lie 10 away and
    # the sides' nearest points 0 to 10 away
    assert metrics.score_case(truth, truth, mask, horizon)["outline_distance"] == 0.0
    assert 4.0 <= on["outline_distance"] <= 10.0 and on["outline_distance"] == off["outline_distance"]


def test_a_blurred_prediction_loses_band_pass_and_gradient_energy():
    mask, truth, horizon = _scene()
    blurred = ndimage.gaussian_filter(truth, 4.0)
    m = metrics.score_case(blurred, truth, mask, horizon)
    assert m["zncc"] > 0.85  # in place and of the right size...
    assert m["bandpass_zncc"] < m["zncc"] - 0.1  # ...but its edges are not where the truth's are
    assert m["gradient_energy"] < 0.3
    noisy = truth + np.random.default_rng(0).normal(0, 0.2, truth.shape)
    assert metrics.score_case(noisy, truth, mask, horizon)["gradient_energy"] > 1.5


def test_darkness_ratios_see_a_lighter_shadow():
    mask, truth, horizon = _scene()
    m = metrics.score_case(0.5 * truth, truth, mask, horizon)
    assert m["dark_ratio"] == pytest.approx(0.5) and m["contact_ratio"] == pytest.approx(0.5)
    assert m["zncc"] == pytest.approx(1.0)  # ZNCC is blind to it


def test_contact_region_lies_next_to_the_feet():
    mask, truth, horizon = _scene()
    contact = metrics.contact_region(mask, metrics.ground_region(mask, horizon))
    rows, cols = np.nonzero(contact)
    assert rows.min() >= 49 and rows.max() <= 49 + 6 and cols.min() >= 40 - 7 and cols.max() <= 55 + 7
    lit = metrics.score_case(truth, np.zeros_like(truth), mask, horizon)
    assert np.isnan(lit["contact_ratio"]) and np.isnan(lit["dark_ratio"])  # no shadow: nothing to compare


# -- scoring ---------------------------------------------------------------------------------------------------
def test_cli_command_adds_the_camera_only_when_asked(tmp_path):
    group = replace(cases.read_groups(FIXTURE)[0])
    cam = score.cli_command("py", FIXTURE, group, 3.0, "camera", tmp_path / "l.png")
    blind = score.cli_command("py", FIXTURE, group, 3.0, "blind", tmp_path / "l.png", "--method geometric")
    assert cam[:4] == ["py", "-m", "ssn_engine", "render"] and "--horizon" in cam and "--fov" in cam
    assert "--horizon" not in blind and blind[-2:] == ["--method", "geometric"]
    assert cam[cam.index("--opacity") + 1] == "1"
    with pytest.raises(ValueError, match="mode"):
        score.cli_command("py", FIXTURE, group, 3.0, "sideways", tmp_path / "l.png")


FAKE_ENGINE = """
import sys, numpy as np
from pathlib import Path
from PIL import Image
args = sys.argv[1:]
cutout = Path(args[3])
light = Path(args[args.index("--light-map") + 1])
s = np.load(cutout.parent / light.name.replace("light_", "truth_").replace(".json", ".npz"))["s"] / 65535
if "--horizon" not in args:
    s = 0.5 * s  # a blind engine that gets the darkness wrong
rgba = np.zeros((*s.shape, 4), np.uint8)
rgba[..., 3] = np.round(255 * s)
Image.fromarray(rgba, "RGBA").save(args[args.index("--layer") + 1])
"""


def test_scoring_runs_the_given_python_and_scores_each_mode(tmp_path):
    repo = tmp_path / "repo"
    (repo / "ssn_engine").mkdir(parents=True)
    (repo / "ssn_engine" / "__init__.py").write_text("")
    (repo / "ssn_engine" / "__main__.py").write_text(FAKE_ENGINE)
    data = tmp_path / "data"
    shutil.copytree(FIXTURE, data)
    cases.write_groups(data, cases.read_groups(data)[:1])  # one group: six engine runs
    result = score.run_scoring(data, tmp_path / "out", repo, sys.executable, log=lambda _: None)
    summary = result["summary"]
    assert summary["camera"]["angle"]["all"]["zncc"] > 0.999
    assert summary["camera"]["angle"]["all"]["dark_ratio"] == pytest.approx(1.0, abs=0.01)
    assert summary["blind"]["angle"]["all"]["dark_ratio"] == pytest.approx(0.5, abs=0.01)
    assert set(summary["camera"]["angle"]) == {"all", "0.53", "3.0", "12.0"}
    assert len(result["cases"]) == 2 * 3 * len(cases.read_groups(data))
    assert not list((tmp_path / "out").rglob("*.part.png"))  # every layer renamed into place
    table = (tmp_path / "out" / "table.md").read_text()
    assert "blind (camera inferred)" in table and "| 12.0 deg |" in table
    stamp = score.prediction_path(tmp_path / "out", "camera", cases.read_groups(data)[0], 3.0).stat().st_mtime_ns
    score.run_scoring(data, tmp_path / "out", repo, sys.executable, log=lambda _: None)  # resumes: nothing re-run
    assert (
        score.prediction_path(tmp_path / "out", "camera", cases.read_groups(data)[0], 3.0).stat().st_mtime_ns == stamp
    )


def test_a_failing_engine_is_reported_with_its_output(tmp_path):
    repo = tmp_path / "repo"
    (repo / "ssn_engine").mkdir(parents=True)
    (repo / "ssn_engine" / "__init__.py").write_text("")
    (repo / "ssn_engine" / "__main__.py").write_text("raise SystemExit('no model here')")
    with pytest.raises(RuntimeError, match="no model here"):
        score.run_scoring(FIXTURE, tmp_path / "out", repo, sys.executable, modes=["camera"], log=lambda _: None)


def test_the_real_cli_makes_a_canvas_sized_shadow_for_a_fixture_case(tmp_path):
    group = cases.read_groups(FIXTURE)[0]
    layer = tmp_path / "layer.png"
    score.run_cli(score.cli_command(sys.executable, FIXTURE, group, 12.0, "camera", layer), ROOT, layer)
    pred = score.read_layer(layer, (group.height, group.width))
    truth = cases.read_truth(FIXTURE, group, 12.0)
    region = metrics.ground_region(cases.read_mask(FIXTURE, group), group.horizon)
    assert metrics.region_zncc(pred, truth, region) > 0.3  # the product casts its shadow roughly where the truth is


def _write_truth_as_predictions(out: Path, mode: str = "camera") -> None:
    for group in cases.read_groups(FIXTURE):
        for angle in cases.ANGLES:
            s = cases.read_truth(FIXTURE, group, angle)
            rgba = np.zeros((*s.shape, 4), np.uint8)
            rgba[..., 3] = np.round(255 * s)
            path = score.prediction_path(out, mode, group, angle)
            path.parent.mkdir(parents=True, exist_ok=True)
            Image.fromarray(rgba, "RGBA").save(path)


def test_sheet_shows_truth_beside_prediction_for_each_size(tmp_path):
    _write_truth_as_predictions(tmp_path / "pred")
    names = [g.name for g in cases.read_groups(FIXTURE)]
    sheet.write_sheet(FIXTURE, [tmp_path / "pred"], tmp_path / "sheet.png", names)
    with Image.open(tmp_path / "sheet.png") as im:
        img = np.asarray(im)
    panel_h = round(sheet.PANEL_WIDTH * 192 / 256)
    assert img.shape == (len(names) * (panel_h + sheet.LABEL), 6 * sheet.PANEL_WIDTH)
    top = img[sheet.LABEL : sheet.LABEL + panel_h]
    truth, pred = top[:, : sheet.PANEL_WIDTH], top[:, sheet.PANEL_WIDTH : 2 * sheet.PANEL_WIDTH]
    assert truth.min() < 100 and np.array_equal(truth, pred)  # a perfect prediction looks like the truth
    with pytest.raises(ValueError, match="unknown groups"):
        sheet.write_sheet(FIXTURE, [tmp_path / "pred"], tmp_path / "x.png", ["nope"])
    # two programs side by side under one light size: the truth and each one's prediction
    shutil.copytree(tmp_path / "pred", tmp_path / "other")
    sheet.write_sheet(FIXTURE, [tmp_path / "pred", tmp_path / "other"], tmp_path / "two.png", names, angles=[3.0])
    with Image.open(tmp_path / "two.png") as im:
        assert im.size == (3 * sheet.PANEL_WIDTH, len(names) * (panel_h + sheet.LABEL))


def test_mitsuba_casts_the_same_shadow_as_the_canvas_renderer():
    pytest.importorskip("mitsuba")
    from training.canvas_eval.mitsuba_check import mitsuba_shadow, random_cap

    mesh = _box_on_ground()
    canvas = render.canvas_camera(mesh.vertices, 64, 48, 15.0)
    dirs = canvas.camera.to_world(disk.disk_directions(30.0, -30.0, 12.0, 64, np.random.default_rng(2)))
    s = render.disk_shadow(mesh.vertices, mesh.faces, meshes.topology(mesh), canvas, dirs)
    g, down = canvas.camera.ground_points()
    ours = s[down[:48]]
    theirs = mitsuba_shadow(mesh.vertices, mesh.faces, g[:48][down[:48]], dirs)
    assert ours.max() > 0.9 and np.abs(ours - theirs).max() < 1e-3
    cap = random_cap(30.0, -30.0, 12.0, 500, np.random.default_rng(0))
    off = np.degrees(np.arccos(np.clip(cap @ direction(np.radians(30.0), np.radians(-30.0)), -1, 1)))
    assert off.max() <= 6.0 and abs((off <= 3.0).mean() - 0.25) < 0.06


def test_a_subset_of_groups_keeps_the_pitches_even_and_the_shapes_distinct():
    items = [_item(f"s{i}", "object" if i < 4 else "animal", f"c{i}") for i in range(6)]
    groups = cases.make_groups(items, 2, 64, 48)
    picked = score.spread(groups, 6)
    assert sorted(g.pitch for g in picked) == [0.0, 0.0, 15.0, 15.0, 30.0, 30.0]
    assert len({g.shape for g in picked}) == 6
    assert score.spread(groups, None) == groups == score.spread(groups, 99)
    with pytest.raises(ValueError, match="at least 1"):
        score.spread(groups, 0)


def test_scoring_an_unfinished_set_names_the_missing_truths(tmp_path):
    data = tmp_path / "data"
    shutil.copytree(FIXTURE, data)
    group = cases.read_groups(data)[1]
    cases.truth_path(data, group, 12.0).unlink()
    with pytest.raises(FileNotFoundError, match="1 truths are missing.*render"):
        score.run_scoring(data, tmp_path / "out", ROOT, sys.executable, log=lambda _: None)


def test_the_oracle_casts_the_true_solid_as_the_renderer_does():
    """The oracle's segments from the first to the last surface along each pixel's ray cast the box's own
    shadow (the renderer's, one direction): as large and in the same place."""
    mesh = _box_on_ground()
    v = np.ascontiguousarray(meshes.yawed(mesh.vertices, 20.0))
    canvas = render.canvas_camera(v, 320, 240, 15.0)
    w = light_direction((150.0 + 180.0) / 360.0, 1.0 - 35.0 / 90.0)  # elevation 35, azimuth 150: behind the camera
    truth = render.disk_shadow(v, mesh.faces, meshes.topology(mesh), canvas, w[None])
    front, back = oracle.surface_depths(v, mesh.faces, canvas.camera, 320, 240, oracle.SUPERSAMPLE)
    yy, xx = np.nonzero(np.isfinite(front))
    cols, rows = (xx + 0.5) / oracle.SUPERSAMPLE, (yy + 0.5) / oracle.SUPERSAMPLE
    solid = oracle.cast(canvas.camera, cols, rows, front[yy, xx], back[yy, xx], w, (240, 320))
    mask = render.canvas_mask(v, mesh.faces, meshes.topology(mesh), canvas)
    ground = metrics.ground_region(mask, canvas.horizon)
    assert truth[ground].sum() > 500  # a shadow worth comparing lies on the visible ground
    assert metrics.region_zncc(solid, truth, ground) > 0.95
    assert solid[ground].sum() == pytest.approx(truth[ground].sum(), rel=0.1)


def test_the_product_given_the_true_pixel_heights_casts_the_renderer_s_shadow():
    """The oracle's true pixel heights (each frame pixel's visible surface's foot less its row) of a box on the
    ground: its lowest pixels stand on their own rows, its top's feet lie below them, its far surface's feet
    behind them; the product's tracer given them (with or without the far surface) casts the renderer's own
    shadow under a 0.53-degree sun."""
    mesh = _box_on_ground()
    v = np.ascontiguousarray(meshes.yawed(mesh.vertices, 20.0))
    canvas = render.canvas_camera(v, 320, 240, 15.0)
    w = light_direction((150.0 + 180.0) / 360.0, 1.0 - 35.0 / 90.0)  # elevation 35, azimuth 150: behind the camera
    truth = render.disk_shadow(v, mesh.faces, meshes.topology(mesh), canvas, w[None])
    mask = render.canvas_mask(v, mesh.faces, meshes.topology(mesh), canvas)
    alpha = np.round(mask * 255).astype(np.uint8)
    session = ShadowSession(alpha, load_method("ssn").method, canvas.horizon, canvas.fov)
    heights, far = oracle.true_heights(v, mesh.faces, canvas.camera, (240, 320), session)
    covered = session.mask > 0.5
    rows = np.flatnonzero(covered.any(axis=1))
    lowest = covered[rows[-1] - 1]
    assert np.abs(heights[rows[-1] - 1][lowest]).max() < 2.0  # frame rows: on the ground
    assert heights[rows[0] + 1][covered[rows[0] + 1]].min() > 5.0  # the top stands above its feet
    assert np.all(far[covered] <= heights[covered] + 0.5)  # its back's feet lie behind its front's, higher up
    assert (heights - far)[covered].max() > 5.0
    u, v_ = (150.0 + 180.0) / 360.0, 1.0 - 35.0 / 90.0
    ground = metrics.ground_region(mask, canvas.horizon)
    assert truth[ground].sum() > 500
    for given_heights in (heights[None], np.stack([heights, far])):  # as deep as the outline says; as the box is
        given = ShadowSession(
            alpha, cast(Any, oracle.GivenHeights(session.method, given_heights)), canvas.horizon, canvas.fov
        )
        shadow = oracle.on_canvas(CanvasShadow(*given.tracer.shadow(u, v_, 0.53, given.framing)), (240, 320))
        assert metrics.region_zncc(shadow, truth, ground) > 0.9


def test_the_product_given_a_floating_box_s_true_geometry_casts_the_renderer_s_shadow():
    """A box floating half its height: the engine reads its image as the same box standing, scaled about the
    camera's centre down to the ground (``standing_shape``, whose pixel heights a perfect surface model reads),
    and floats that by the lift; given those heights and the true lift, the product's tracer casts the renderer's
    shadow of the floating box, and without the lift it does not."""
    mesh = _box_on_ground()
    v = np.ascontiguousarray(meshes.yawed(mesh.vertices, 20.0))
    v[:, 1] += 0.5
    canvas = render.canvas_camera(v, 320, 240, 15.0)
    standing = oracle.standing_shape(v, canvas.camera)
    assert standing[:, 1].min() == pytest.approx(0.0, abs=1e-9)
    assert np.allclose(canvas.camera.project(standing), canvas.camera.project(v))  # the same image
    w = light_direction((150.0 + 180.0) / 360.0, 1.0 - 35.0 / 90.0)  # elevation 35, azimuth 150: behind the camera
    truth = render.disk_shadow(v, mesh.faces, meshes.topology(mesh), canvas, w[None])
    mask = render.canvas_mask(v, mesh.faces, meshes.topology(mesh), canvas)
    alpha = np.round(mask * 255).astype(np.uint8)
    session = ShadowSession(alpha, load_method("ssn").method, canvas.horizon, canvas.fov)
    heights = oracle.true_heights(standing, mesh.faces, canvas.camera, (240, 320), session)
    given = ShadowSession(alpha, cast(Any, oracle.GivenHeights(session.method, heights)), canvas.horizon, canvas.fov)
    ground = metrics.ground_region(mask, canvas.horizon)
    assert truth[ground].sum() > 500
    u, v_ = (150.0 + 180.0) / 360.0, 1.0 - 35.0 / 90.0
    scores = []
    for lift in (true_lift(v, mesh.faces, canvas, mask), 0.0):
        given.set_geometry(lift)
        shadow = oracle.on_canvas(CanvasShadow(*given.tracer.shadow(u, v_, 0.53, given.framing)), (240, 320))
        scores.append(metrics.region_zncc(shadow, truth, ground))
    assert scores[0] > 0.85 and scores[1] < 0.5  # (0.90 and 0.00 here)
