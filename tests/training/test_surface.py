"""The surface model's data and training (training.surface): pixel heights of a mesh's visible surface, the
packed views, a training run and its installation into a model folder."""

from __future__ import annotations

import json
import shutil
from pathlib import Path

import numpy as np
import pytest

from ssn_engine.camera import Camera
from ssn_engine.methods import load_method
from ssn_engine.methods.onnx_ssn import OnnxSSN
from training.data.procedural import procedural_items
from training.data import meshes
from training.data.surface_views import R, load, make, pixel_heights, save, stretched
from training.data.views import VIEWS

pytest.importorskip("torch")

ROOT = Path(__file__).resolve().parents[2]


def _box(half: float = 0.2, height: float = 1.0) -> tuple[np.ndarray, np.ndarray]:
    """A box standing on the ground, centred on the origin: vertices (8, 3) and triangles (12, 3)."""
    v = np.array([[x, y, z] for x in (-half, half) for y in (0.0, height) for z in (-half, half)], np.float64)
    quads = [(0, 1, 3, 2), (4, 6, 7, 5), (0, 4, 5, 1), (2, 3, 7, 6), (0, 2, 6, 4), (1, 5, 7, 3)]
    return v, np.array([t for a, b, c, d in quads for t in ((a, b, c), (a, c, d))], np.int64)


def test_a_box_s_front_stands_on_its_bottom_edge_and_its_top_reaches_back():
    """Looking down at a box: its front face's pixels have their feet on the face's bottom edge (the lowest row of
    their column); its top face's, farther back, higher in the picture."""
    vertices, faces = _box()
    cam = Camera(R, 0.5, fov=40.0, pitch=25.0).frame_top(vertices)
    h, far = pixel_heights(vertices, faces, cam)
    col = R // 2
    covered = np.flatnonzero(np.isfinite(h[:, col]))
    feet = h[covered, col] + covered + 0.5
    bottom = covered[-1] + 1.0
    front_edge = cam.project_xyz(np.array([0.0]), np.array([1.0]), np.array([0.2]))[1][0]  # the top front edge
    front = covered + 0.5 > front_edge
    assert front.sum() > 10 and (~front).sum() > 5
    assert np.abs(feet[front] - bottom).max() < 1.0
    top = feet[~front]  # the top face's feet: behind the front's, the farther the higher in the picture
    assert np.all(np.diff(top) > 0) and top[-1] < bottom and top[0] < bottom - 10.0
    # the far surface lies behind: across the front face, the back face (feet on its bottom edge) or, low down,
    # the bottom (on the ground: feet on the pixel's own row), whichever is lower in the picture
    far_feet = far[covered, col] + covered + 0.5
    assert np.all(far_feet <= feet + 1e-3)
    back = cam.project_xyz(np.array([0.0]), np.array([0.0]), np.array([-0.2]))[1][0]  # the bottom back edge
    assert np.abs(far_feet[front] - np.maximum(back, covered + 0.5)[front]).max() < 1.5
    assert (far_feet[front] < feet[front] - 10.0).sum() > 5


def test_a_stretched_shape_is_another_shape_standing_as_the_conventions_say():
    """--stretch: each view's shape scaled along x, y and z by its own factors (at most 1 + stretch either way),
    normalised again (AABB diagonal 1, standing on y = 0), its triangles unchanged."""
    v, f = _box(0.2, 1.0)
    box = meshes.normalise(meshes.Mesh(v, f.astype(np.int32)))
    ratios = []
    for k in range(20):
        out = stretched(box, np.random.default_rng(k), 0.5)
        ext = np.ptp(out.vertices, axis=0)
        assert np.linalg.norm(ext) == pytest.approx(1.0) and out.vertices[:, 1].min() == pytest.approx(0.0)
        np.testing.assert_array_equal(out.faces, box.faces)
        ratios.append((ext / np.ptp(box.vertices, axis=0)) / (ext[1] / np.ptp(box.vertices, axis=0)[1]))
    ratios = np.array(ratios)[:, [0, 2]]  # width and depth over height, against the box's own
    assert ratios.min() >= 1 / 1.5**2 - 1e-9 and ratios.max() <= 1.5**2 + 1e-9
    assert ratios.min() < 0.8 and ratios.max() > 1.25  # flatter and stockier boxes among them


def test_views_travel_packed_and_come_back(tmp_path):
    rng = np.random.default_rng(0)
    mask = np.zeros((R, R), np.float32)
    mask[30:90, 50:70] = 1.0
    height = np.where(mask > 0, rng.uniform(20, 100, (R, R)), np.nan).astype(np.float32)
    depth = rng.uniform(0, 20, (R, R)).astype(np.float32)
    view = {"mask": mask, "camera": (10.0, 150.0), "height": height, "far": height - depth}
    save(tmp_path / "v.npz", [view] * 2, [15.0, 20.0])
    back = load([tmp_path / "v.npz"])
    assert back["mask"].shape == (2, R, R) and np.array_equal(back["mask"][1], mask)
    assert np.abs(back["height"][0] - np.nan_to_num(height)).max() <= 0.25  # half rows, rounded
    assert np.abs(back["depth"][0] - depth * mask).max() <= 0.25
    assert np.allclose(back["camera"][0], np.array([10.0, 150.0]) / R) and list(back["pitch"]) == [15.0, 20.0]


def test_a_set_of_one_source_holds_its_items_views_alone(tmp_path):
    """``make --sources procedural``: the split's procedural shapes, every view of each, no meshes or people."""
    make("val", ["continuous"], tmp_path / "p.npz", seed=3, sources=("procedural",))
    views = load([tmp_path / "p.npz"])
    shapes = [it for it in procedural_items(36, 3) if it.split == "val"]
    assert len(shapes) >= 2 and len(views["mask"]) == len(shapes) * VIEWS
    assert (views["mask"].sum(axis=(1, 2)) > 50).all() and (views["height"] > 0).any()


def test_the_depth_s_weighted_loss_leans_an_unsure_reading_to_the_deep_pixels():
    """Two pixels of one outline, one flat and one 40 rows deep: read as either, the plain L1 is level; the depth's
    loss weighted (``--depth-weight 4``) prefers the deep reading, and leaves the pixel height's loss a plain
    mean."""
    import torch

    from training.surface_model import loss_terms

    mask = torch.zeros(1, 1, R, R)
    mask[0, 0, 0, :2] = 1.0
    target = torch.zeros(1, 2, R, R)
    target[0, 1, 0, 1] = 40.0 / R

    def l1(height: float, depth: float, weight: float) -> float:
        pred = torch.zeros(1, 2, R, R)
        pred[0, 0], pred[0, 1] = height / R, depth / R
        return float(loss_terms(pred, target, mask, weight)[0]) * R

    assert l1(0.0, 40.0, 0.0) == pytest.approx(l1(0.0, 0.0, 0.0), rel=1e-5)
    assert l1(0.0, 40.0, 4.0) < 0.5 * l1(0.0, 0.0, 4.0)
    assert l1(4.0, 0.0, 4.0) - l1(0.0, 0.0, 4.0) == pytest.approx(4.0, rel=1e-5)


def test_a_short_training_run_installs_into_a_model_folder(tmp_path, monkeypatch):
    """A few steps on the CPU of a network reading the depth too, then installed: the graph within 1e-4 of torch,
    model.json naming it, the engine reading both surfaces' pixel heights through it; installed with a second
    graph, each pixel stands at least as high as the first reads it."""
    from training.onnx_graphs import session
    from training.surface_model import install, train

    rng = np.random.default_rng(1)
    views = []
    for _ in range(4):
        mask = np.zeros((R, R), np.float32)
        top, left = rng.integers(10, 50, 2)
        mask[top : top + 60, left : left + 20] = 1.0
        rows = np.arange(R, dtype=np.float32)[:, None] + 0.5
        height = np.where(mask > 0, top + 60 - rows, np.nan)
        views.append({"mask": mask, "camera": (20.0, 160.0), "height": height, "far": height - 6.0})
    save(tmp_path / "data" / "train.npz", views, [10.0] * 4)
    save(tmp_path / "data" / "val.npz", views[:2], [10.0] * 2)
    train(
        tmp_path / "data",
        [tmp_path / "data" / "train.npz"],
        tmp_path / "run",
        0.02,
        2,
        1e-3,
        "cpu",
        0,
        (4, 8, 8),
        depth=True,
    )
    log = [json.loads(line) for line in (tmp_path / "run" / "log.jsonl").read_text().splitlines()]
    assert log[-1]["step"] >= 1 and np.isfinite(log[-1]["val mae"]) and np.isfinite(log[-1]["val depth"])
    models = tmp_path / "models"
    shutil.copytree(ROOT / "ssn_engine" / "models", models)
    assert install(tmp_path / "run" / "last.pt", models) < 1e-4
    # mirror-averaged: a mirrored mask, the same camera, reads as the mirror image of the mask's reading
    graph = session(models / "surface.onnx")
    mask = (rng.random((1, 1, R, R)) > 0.5).astype(np.float32)
    camera = np.array([[0.3, 1.1]], np.float32)
    direct = graph.run(None, {"mask": mask, "camera": camera})[0]
    mirrored = graph.run(None, {"mask": np.ascontiguousarray(mask[..., ::-1]), "camera": camera})[0]
    assert np.abs(mirrored[..., ::-1] - direct).max() < 1e-5
    card = json.loads((models / "model.json").read_text())
    assert card["surface"] == "surface.onnx" and "steps of 2 views" in card["surface_training"]
    assert (models / "MODEL_CARD.md").read_text().count("## Surface model") == 1
    monkeypatch.setenv("SSN_SHADOW_MODEL_DIR", str(models))
    frame = np.zeros((1, 256, 256), np.float32)
    frame[0, 60:200, 100:140] = 1.0
    method = load_method("ssn").method
    assert isinstance(method, OnnxSSN)
    heights = method.pixel_heights(frame, np.array([[40.0, 300.0]]))  # the visible surface's, and the far one's
    assert heights is not None and heights.shape == (1, 2, 256, 256) and np.isfinite(heights).all()
    assert np.all(heights[0, 1] <= heights[0, 0] + 1e-3)
    # installed without --second, the folder's second surface graph went; with it, it is kept and named
    assert not (models / "surface_second.onnx").exists() and "surface_second" not in card
    shipped = ROOT / "ssn_engine" / "models" / "surface_second.onnx"
    install(tmp_path / "run" / "last.pt", models, second=shipped)
    card = json.loads((models / "model.json").read_text())
    assert card["surface_second"] == "surface_second.onnx" and (models / "surface_second.onnx").is_file()
    assert "each pixel's height the higher of this reading and surface_second.onnx's" in card["surface_training"]
    paired = load_method("ssn").method
    assert isinstance(paired, OnnxSSN)
    raised = paired.pixel_heights(frame, np.array([[40.0, 300.0]]))
    assert raised is not None and np.all(raised[0, 0] >= heights[0, 0] - 0.5)


def test_the_shipped_graph_is_fine_tuned_where_its_runs_are_gone(tmp_path):
    """``train --init ssn_engine/models/surface.onnx``: the installed graph's network rebuilt (its reading the
    graph's), trained on, and installed again with its earlier stages in the record."""
    from training.onnx_graphs import session
    from training.surface_model import install, start_from, train

    graph = ROOT / "ssn_engine" / "models" / "surface.onnx"
    net, history = start_from(graph)
    shipped = json.loads((ROOT / "ssn_engine" / "models" / "model.json").read_text())["surface_training"]
    stages = shipped.split("], ", 1)[1].split("; validation")[0]  # its widths and scores are the new record's
    assert history == [stages] and stages.startswith("7942 steps of 64 views")
    mask = np.zeros((1, 1, R, R), np.float32)
    mask[0, 0, 40:110, 50:80] = 1.0
    camera = np.array([[0.25, 1.2]], np.float32)
    import torch

    with torch.no_grad():  # the graph averages the mask's reading with its mirror image's
        mine = 0.5 * (
            net(torch.from_numpy(mask), torch.from_numpy(camera))
            + net(torch.from_numpy(np.ascontiguousarray(mask[..., ::-1])), torch.from_numpy(camera)).flip(-1)
        )
    theirs = session(graph).run(None, {"mask": mask, "camera": camera})[0]
    assert np.abs(mine.clamp(0, 1).numpy() - theirs).max() < 1e-3
    rows = np.arange(R, dtype=np.float32)[:, None] + 0.5
    height = np.where(mask[0, 0] > 0, 110 - rows, np.nan)
    views = [{"mask": mask[0, 0], "camera": (32.0, 150.0), "height": height, "far": height}]
    save(tmp_path / "data" / "train.npz", views * 2, [10.0] * 2)
    save(tmp_path / "data" / "val.npz", views, [10.0])
    train(tmp_path / "data", [tmp_path / "data" / "train.npz"], tmp_path / "run", 0.01, 2, 1e-4, "cpu", 0, init=graph)
    models = tmp_path / "models"
    shutil.copytree(ROOT / "ssn_engine" / "models", models)
    assert install(tmp_path / "run" / "last.pt", models) < 1e-4
    record = json.loads((models / "model.json").read_text())["surface_training"]
    assert record.startswith(f"widths [16, 32, 64, 128, 192, 256], {stages}; then ") and "steps of 2 views" in record
    assert record.count("widths") == 1 and record.count("validation") == 1
    # ``average``: the weights part of the way from the graph to the fine-tuned ones; none of the way reads as the
    # graph, and the record says what was averaged
    from training.surface_model import average, load_checkpoint

    tuned = load_checkpoint(tmp_path / "run" / "last.pt").state_dict()
    for share in (0.0, 0.25):
        row = average(graph, tmp_path / "run" / "last.pt", share, tmp_path / "data", tmp_path / f"avg{share}.pt")
        assert np.isfinite(row["val mae"])
    between = load_checkpoint(tmp_path / "avg0.25.pt").state_dict()
    start = net.state_dict()
    key = next(k for k in start if k.endswith("weight") and start[k].ndim == 4 and not torch.equal(start[k], tuned[k]))
    want = 0.75 * start[key] + 0.25 * tuned[key]
    assert torch.allclose(between[key], want, atol=2e-3 * float(want.abs().max()))
    with torch.no_grad():
        none = load_checkpoint(tmp_path / "avg0.0.pt")(torch.from_numpy(mask), torch.from_numpy(camera))
        assert np.abs(none.numpy() - net(torch.from_numpy(mask), torch.from_numpy(camera)).numpy()).max() < 2e-3
    install(tmp_path / "avg0.25.pt", models)
    record = json.loads((models / "model.json").read_text())["surface_training"]
    assert "; then averaged with surface.onnx: 0.25 of these weights, 0.75 of its; validation" in record
    with pytest.raises(ValueError, match="share"):
        average(graph, tmp_path / "run" / "last.pt", 1.5, tmp_path / "data", tmp_path / "bad.pt")


def test_a_run_cut_short_goes_on_where_it_stopped(tmp_path, monkeypatch):
    """``train --resume``: the second call continues the first's steps, time and stage (one stage in the record,
    its steps the sum), appending to the log, from the saved optimiser."""
    import training.surface_model as surface_model

    monkeypatch.setattr(surface_model, "VAL_EVERY", 2)
    mask = np.zeros((R, R), np.float32)
    mask[30:90, 50:70] = 1.0
    rows = np.arange(R, dtype=np.float32)[:, None] + 0.5
    height = np.where(mask > 0, 90 - rows, np.nan)
    views = [{"mask": mask, "camera": (20.0, 160.0), "height": height, "far": height - 3.0}] * 2
    save(tmp_path / "data" / "train.npz", views, [10.0] * 2)
    save(tmp_path / "data" / "val.npz", views[:1], [10.0])
    args = (tmp_path / "data", [tmp_path / "data" / "train.npz"], tmp_path / "run")
    surface_model.train(*args, 0.01, 2, 1e-3, "cpu", 0, (4, 8, 8))
    first = torch_load(tmp_path / "run" / "last.pt")
    assert first["step"] >= 1 and "optimizer" in first and len(first["history"]) == 1
    surface_model.train(*args, 0.1, 2, 1e-3, "cpu", 0, (4, 8, 8), resume=True)
    second = torch_load(tmp_path / "run" / "last.pt")
    assert second["step"] > first["step"] and second["seconds"] > first["seconds"]
    assert len(second["history"]) == 1 and second["history"][0]["steps"] == second["step"]
    log = [json.loads(line) for line in (tmp_path / "run" / "log.jsonl").read_text().splitlines()]
    assert [r["step"] for r in log] == sorted(r["step"] for r in log) and log[-1]["step"] == second["step"]
    assert any(r["step"] <= first["step"] for r in log) and not (tmp_path / "run" / "last.part").exists()


def torch_load(path: Path) -> dict:
    import torch

    return torch.load(path, map_location="cpu", weights_only=True)
