"""The camera estimator (training.camera_estimator): its graph's reading, training, export and installation."""

from __future__ import annotations

import json
import shutil
from pathlib import Path

import numpy as np
import pytest

from training.data import meshes
from training.data.procedural import box
from training.data.camera_views import view_record

torch = pytest.importorskip("torch")

ROOT = Path(__file__).resolve().parents[2]


def test_the_graph_reads_the_median_of_its_horizon_distribution(monkeypatch):
    """Bins 3 and 4 share the mass 1 : 3, so the median lies a third of the way into bin 4; the focal length
    comes back de-standardised."""
    from training.camera_net import EDGES, FOCAL_MEAN, FOCAL_STD, CameraNet

    net = CameraNet(width=8).eval()
    logits = torch.full((1, len(EDGES)), -1e4)
    logits[0, 3], logits[0, 4] = 0.0, float(np.log(3.0))
    logits[0, -1] = 0.5  # the standardised focal length
    monkeypatch.setattr(net, "raw", lambda x: logits.expand(len(x), -1))
    horizon, focal = net(torch.zeros(2, 1, 64, 64))[0].tolist()
    width = EDGES[1] - EDGES[0]
    assert horizon == pytest.approx(EDGES[4] + width / 3, abs=1e-5)
    assert focal == pytest.approx(FOCAL_MEAN + 0.5 * FOCAL_STD)


def _box_views(tmp_path: Path, sharp: bool = False) -> None:
    """A box seen from a few cameras, as `training.heights make` writes views, for both splits (``sharp``: with the
    estimator's inputs made from the masks at N = 256, as `make` writes them)."""
    mesh = meshes.normalise(box((0.5, 0.35, 0.3), (0.0, 0.175, 0.0)))
    topo = meshes.topology(mesh)
    views = [view_record(mesh, topo, yaw, pitch, 45.0) for yaw, pitch in ((0.0, 0.0), (60.0, 15.0), (120.0, 30.0))]
    data = {"mask": np.stack([v["mask"] for v in views]).astype(np.float16)}
    data |= {"camera": np.array([v["camera"] for v in views]), "kind": np.zeros(3, int), "pitch": np.array([0, 15, 30])}
    if sharp:
        data["estimator"] = np.stack([np.round(v["estimator"] * 255).astype(np.uint8) for v in views])
        data["estimator_camera"] = np.stack([v["estimator_camera"] for v in views])
    for split in ("train", "val"):
        np.savez(tmp_path / f"{split}_box.npz", **data)


def test_the_estimator_trains_exports_and_installs_into_a_model(tmp_path):
    """A short run exports a graph that matches the network; installed into a copy of the shipped model, a blind
    call reads its camera from the mask and renders what a call given that camera renders."""
    from ssn_engine.methods import OnnxSSN
    from training.camera_estimator import main
    from training.camera_net import CameraNet, examples, weights_from_graph

    _box_views(tmp_path)
    run = tmp_path / "run"
    main(["--data", str(tmp_path), "--out", str(run), "--minutes", "0.05", "--batch", "4", "--val-every", "1"])
    summary = json.loads((run / "camera.json").read_text())
    assert summary["train_views"] == 3 and summary["history"]
    assert summary["val"]["objects"]["views"] == 3 and summary["val"]["animals"]["views"] == 0  # errors by kind
    net = CameraNet()
    net.load_state_dict(torch.load(run / "camera.pt"))
    x, _, _, _ = examples(tmp_path, "val")
    import onnxruntime as ort

    graph = ort.InferenceSession(str(run / "camera.onnx"), providers=["CPUExecutionProvider"])
    with torch.no_grad():
        expected = net.eval()(torch.from_numpy(x[:, None])).numpy()
    np.testing.assert_allclose(graph.run(["camera"], {"mask": x[:, None]})[0], expected, atol=1e-4)
    rebuilt = weights_from_graph(run / "camera.onnx", CameraNet())  # --init-from: a fine-tune starts from the graph
    assert all(torch.equal(rebuilt[k], v) for k, v in net.state_dict().items())

    folder = tmp_path / "model"
    shutil.copytree(ROOT / "ssn_engine" / "models", folder)
    main(["--out", str(run), "--minutes", "0", "--install", str(folder)])
    assert json.loads((folder / "model.json").read_text())["camera"] == "camera.onnx"
    assert (folder / "MODEL_CARD.md").read_text().count("## Camera estimator") == 1
    model = OnnxSSN(folder)
    mask = np.zeros((1, 256, 256), np.float32)
    mask[0, 60:200, 110:150] = 1.0
    cameras = model.cameras_for(mask, None)
    assert cameras.shape == (1, 2) and np.isfinite(cameras).all()
    elm = np.zeros((1, 16, 32), np.float32)
    elm[0, 10, 20] = 1.0
    ao = model.predict_ao(mask)  # blind: the plain AOP (a given camera gets the camera-taking one)
    np.testing.assert_array_equal(model.render(mask, ao, elm), model.render(mask, ao, elm, cameras))

    # a fine-tune of the installed graph (--init-from): its record keeps the training it started from
    before = json.loads((folder / "model.json").read_text())["camera_training"]
    tuned = tmp_path / "tuned"
    main(
        ["--data", str(tmp_path), "--out", str(tuned), "--minutes", "0.05", "--batch", "4", "--val-every", "1"]
        + ["--init-from", str(folder / "camera.onnx"), "--install", str(folder)]
    )
    after = json.loads((folder / "model.json").read_text())["camera_training"]
    assert after.startswith(before + "; then fine-tuned on 3 train views")


def test_kind_weights_draw_a_kind_more_often():
    """``--kind-weights 1 1 3``: among views of which a quarter are animals, half the draws are animals."""
    from training.camera_net import sampling_weights

    kinds = np.array([0, 0, 1, 2] * 500)
    weights = sampling_weights(kinds, (1.0, 1.0, 3.0))
    draws = torch.multinomial(weights, 6000, replacement=True, generator=torch.Generator().manual_seed(0))
    assert (kinds[draws.numpy()] == 2).mean() == pytest.approx(0.5, abs=0.03)


def test_other_views_of_the_same_items(tmp_path, monkeypatch):
    """`training.heights make --view-seed`: the same items seen from other cameras (continuous ones drawn anew)."""
    from training import heights
    from training.data import camera_views
    from training.data.sources import all_items

    item = next(it for it in all_items(("procedural",), 36, 0, 0) if it.split == "val")
    monkeypatch.setattr(camera_views, "all_items", lambda *a: [item])
    for seed in (None, 1):
        heights.main(
            ["make", "--split", "val", "--out", str(tmp_path / f"{seed}.npz")] + (["--view-seed", "1"] if seed else [])
        )
    own, other = (np.load(tmp_path / f"{seed}.npz") for seed in (None, 1))
    assert len(own["pitch"]) == len(other["pitch"]) == 15 and (own["kind"] == other["kind"]).all()
    assert not np.allclose(own["pitch"], other["pitch"]) and not np.array_equal(own["mask"], other["mask"])


def test_a_missing_split_is_named(tmp_path):
    from training.camera_estimator import main

    with pytest.raises(SystemExit, match="no train"):
        main(["--data", str(tmp_path), "--out", str(tmp_path / "run"), "--minutes", "0.01"])


def test_examples_written_once_train_without_the_views(tmp_path):
    """``--write-examples`` packs both splits' inputs into one small file (for a GPU machine, where the views do
    not travel); a run given it with ``--examples`` reads the same inputs, to 8 bits, and the same targets."""
    from training.camera_estimator import main
    from training.camera_net import examples

    (tmp_path / "views").mkdir()
    _box_views(tmp_path / "views")
    packed = tmp_path / "examples.npz"
    main(["--data", str(tmp_path / "views"), "--write-examples", str(packed)])
    main(
        ["--examples", str(packed), "--out", str(tmp_path / "run"), "--minutes", "0.05", "--batch", "4"]
        + ["--val-every", "1"]
    )
    assert json.loads((tmp_path / "run" / "camera.json").read_text())["train_views"] == 3
    x, y, pitch, kind = examples(tmp_path / "views", "val")
    with np.load(packed) as data:
        np.testing.assert_allclose(data["val_x"] / 255, x, atol=0.5 / 255 + 1e-6)
        np.testing.assert_array_equal(data["val_y"], y)
        np.testing.assert_array_equal(data["val_pitch"], pitch)
        assert data["train_x"].dtype == np.uint8


def test_the_estimator_learns_from_inputs_as_sharp_as_the_engines(tmp_path):
    """``make`` writes the estimator's input from the mask at the engine's N = 256, as the engine makes it from a
    cutout; with ``--sharp-input`` the estimator trains on it instead of the 128-pixel mask scaled up: the same views
    and targets (within the bounding box's rounding), the silhouette's edge as crisp as in use."""
    from training.camera_net import examples
    from training.data.camera_views import ESTIMATOR_KEYS, load

    (tmp_path / "old").mkdir()
    (tmp_path / "sharp").mkdir()
    _box_views(tmp_path / "old")
    _box_views(tmp_path / "sharp", sharp=True)
    assert set(ESTIMATOR_KEYS) <= set(load([tmp_path / "sharp" / "val_box.npz"]))
    x_old, y_old, _, _ = examples(tmp_path / "sharp", "val")  # the shipped estimator's inputs, unless asked
    x, y, _, _ = examples(tmp_path / "sharp", "val", sharp=True)
    with pytest.raises(SystemExit, match="predate"):
        examples(tmp_path / "old", "val", sharp=True)
    assert x.shape == x_old.shape and x.dtype == np.float32
    np.testing.assert_allclose(y[:, 0], y_old[:, 0], atol=0.02)  # horizon rows over N
    np.testing.assert_allclose(y[:, 1], y_old[:, 1], rtol=0.06)  # focal lengths
    partial = lambda a: ((a > 0.05) & (a < 0.95)).sum()  # noqa: E731
    assert partial(x) < 0.8 * partial(x_old)  # fewer blurred edge pixels


def test_surface_sets_teach_the_estimator_beside_its_own_views(tmp_path):
    """A folder of ``training.surface make`` sets (bit-packed masks, no kinds: the procedural animals, people in
    poses, objects with parts on the ground) trains the estimator too: the same views give nearly the same inputs
    and targets (their masks cut at half coverage), an empty view is left out, and a view of no recorded kind is
    drawn as often as any."""
    from training.camera_net import examples, sampling_weights
    from training.data import surface_views

    (tmp_path / "own").mkdir()
    (tmp_path / "surface").mkdir()
    _box_views(tmp_path / "own")
    mesh = meshes.normalise(box((0.5, 0.35, 0.3), (0.0, 0.175, 0.0)))
    topo = meshes.topology(mesh)
    views = [surface_views.view_record(mesh, topo, yaw, pitch, 45.0) for yaw, pitch in ((0.0, 0.0), (60.0, 15.0))]
    views.append(views[0] | {"mask": np.zeros_like(views[0]["mask"])})  # a speck that binned to nothing
    surface_views.save(tmp_path / "surface" / "val_s.npz", views, [0.0, 15.0, 0.0])
    x_own, y_own, _, _ = examples(tmp_path / "own", "val")
    x, y, pitch, kind = examples(tmp_path / "surface", "val")
    assert len(x) == 2 and list(pitch) == [0.0, 15.0] and (kind < 0).all()
    np.testing.assert_allclose(y[:, 0], y_own[:2, 0], atol=0.02)  # horizon rows over N: the framing follows the
    np.testing.assert_allclose(y[:, 1], y_own[:2, 1], rtol=0.05)  # mask, a pixel less at its edges cut at half
    assert np.abs(x - x_own[:2]).mean() < 0.02
    assert np.allclose(sampling_weights(np.array([-1, 2]), (1.0, 1.0, 3.0)).numpy(), [1.0, 3.0])
