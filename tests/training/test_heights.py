"""Pixel heights and the height proxy: the z-buffer, the pixel-height round trip, the proxy's hard shadows against
ray casting, HeightNet and its graph, and the engine's SR fed the proxy instead of the flat card."""

from __future__ import annotations

import json
import shutil
from pathlib import Path

import numpy as np
import pytest

from ssn_engine.camera import Camera
from ssn_engine.hemisphere import direction
from ssn_engine.methods.height_proxy import HeightProxy, depth_from_heights, proxy_occlusion
from training.data import meshes
from training.data.depth_raster import depth_range
from training.data.procedural import box, rotate_y
from training.data.raycast import ray_hits
from training.data.render_bases import view_camera
from training.heights import R, pixel_heights, view_heights

ROOT = Path(__file__).resolve().parents[2]


def _scene(size=(0.5, 0.35, 0.3), yaw=30.0, n=64, pitch=20.0):
    """A box standing on the ground, turned about the vertical, and the conventions' camera framing it."""
    mesh = meshes.normalise(rotate_y(box(size, (0.0, size[1] / 2, 0.0)), yaw))
    return mesh, view_camera(mesh.vertices, n, 45.0, pitch)


def _slab_depths(mesh: meshes.Mesh, cam: Camera) -> tuple[np.ndarray, np.ndarray]:
    """Near and far depths of every pixel centre's ray through the box, from its faces' planes (ray casting)."""
    rays = cam.pixel_rays().reshape(-1, 3)
    v, f = mesh.vertices, mesh.faces
    a = v[f[:, 0]]
    normal = np.cross(v[f[:, 1]] - a, v[f[:, 2]] - a)
    normal /= np.linalg.norm(normal, axis=1, keepdims=True)
    near = np.full(len(rays), -np.inf)
    far = np.full(len(rays), np.inf)
    for nrm, point in {tuple(np.round(nn, 9)): (nn, p) for nn, p in zip(normal, a, strict=True)}.values():
        denom = rays @ nrm
        t = ((point - cam.centre) @ nrm) / np.where(np.abs(denom) > 1e-12, denom, 1e-12)
        near = np.where(denom < 0, np.maximum(near, t), near)  # entering through a face that faces the camera
        far = np.where(denom > 0, np.minimum(far, t), far)
    hit = near < far
    shape = (cam.n, cam.n)
    return np.where(hit, near, np.inf).reshape(shape), np.where(hit, far, -np.inf).reshape(shape)


def test_the_z_buffer_keeps_the_nearest_and_farthest_surface_of_every_pixel():
    mesh, cam = _scene()
    front, back = depth_range(mesh.vertices, mesh.faces, cam)
    near, far = _slab_depths(mesh, cam)
    seen = np.isfinite(near) & np.isfinite(front)
    assert (np.isfinite(front) != np.isfinite(near)).sum() <= 0.01 * np.isfinite(near).sum()  # edge pixels only
    np.testing.assert_allclose(front[seen], near[seen], atol=1e-5)
    np.testing.assert_allclose(back[seen], far[seen], atol=1e-5)


@pytest.mark.parametrize("pitch", [0.0, 15.0, 30.0])
def test_pixel_heights_and_depths_are_inverse(pitch):
    mesh, cam = _scene(pitch=pitch)
    front, _ = depth_range(mesh.vertices, mesh.faces, cam)
    covered = np.isfinite(front)
    heights = pixel_heights(cam, front)
    assert heights[covered].min() >= -1e-3  # no point of the box is under the ground
    np.testing.assert_allclose(depth_from_heights(cam, heights, covered)[covered], front[covered], rtol=1e-5)
    assert np.all(np.isinf(depth_from_heights(cam, heights, covered)[~covered]))


@pytest.mark.parametrize(("elevation", "azimuth"), [(20.0, 40.0), (45.0, -120.0), (70.0, 180.0)])
def test_the_proxy_of_a_convex_shape_casts_its_exact_hard_shadow(elevation, azimuth):
    """With the true near and far depths, the proxy of a box is the box: its hard shadow agrees with rays cast
    from every ground point towards the light except along the shadow's edge."""
    mesh, cam = _scene()
    front, back = depth_range(mesh.vertices, mesh.faces, cam)
    ground, valid = cam.ground_points()
    points = ground[valid]
    w = cam.to_world(direction(np.radians(elevation), np.radians(azimuth)))
    got = proxy_occlusion(cam, front, back, w[None], points, float(mesh.vertices[:, 1].max()))[0] > 0.5
    want = ray_hits(points + 1e-6 * w, np.repeat(w[None], len(points), 0), mesh.vertices, mesh.faces)
    assert want.sum() > 50
    assert (got != want).sum() <= 0.08 * want.sum()


def test_a_lower_sun_throws_a_longer_proxy_shadow():
    """A pole's proxy shadow on the ground reaches its height / tan(elevation) beyond the pole, away from the
    light."""
    mesh, cam = _scene(size=(0.15, 0.8, 0.15))
    front, back = depth_range(mesh.vertices, mesh.faces, cam)
    top = float(mesh.vertices[:, 1].max())
    x, z = np.meshgrid(np.linspace(-4, 4, 321), np.linspace(-4, 4, 321))
    ground = np.stack([x.ravel(), np.zeros(x.size), z.ravel()], axis=1)
    for elevation in (60.0, 30.0, 15.0):
        w = cam.to_world(direction(np.radians(elevation), np.radians(90.0)))  # the light on the right
        hit = proxy_occlusion(cam, front, back, w[None], ground, top)[0] > 0.5
        reach = -ground[hit, 0].min()  # the shadow falls to the left (-x)
        assert ground[hit, 0].max() < 0.15  # nothing on the lit side beyond the footprint
        far_edge = -float(mesh.vertices[:, 0].min())  # the pole's left side, where its shadow starts
        assert reach == pytest.approx(far_edge + top / np.tan(np.radians(elevation)), rel=0.1)


def test_view_heights_describe_the_view():
    mesh, _ = _scene()
    view = view_heights(mesh, meshes.topology(mesh), 0.0, 15.0, 45.0)
    covered = view["mask"] > 0.5
    assert view["mask"].shape == view["front"].shape == view["back"].shape == (R, R)
    assert covered.sum() > 100
    assert np.all(view["back"][covered] <= view["front"][covered] + 1e-3)  # the far side is nearer its foot
    assert view["front"][covered].max() > 5  # rows: the box stands tall in the frame
    horizon, focal = view["camera"]
    assert horizon < np.flatnonzero(covered.any(axis=1))[-1]  # looking down: the horizon above the base


def _height_graph(tmp_path: Path) -> Path:
    """An untrained HeightNet's graph (random weights) through the export and its parity check."""
    torch = pytest.importorskip("torch")
    from training.heights import export
    from training.model.unet import HeightNet, UNetConfig

    torch.manual_seed(0)
    ck = tmp_path / "hnet.pt"
    torch.save({"net": HeightNet(UNetConfig()).state_dict()}, ck)
    path = tmp_path / "height.onnx"
    assert export(ck, path) < 1e-4
    return path


def test_the_height_proxy_is_the_shipped_srs_card_when_a_model_names_a_height_graph(tmp_path):
    from ssn_engine.methods import OnnxSSN

    folder = tmp_path / "model"
    shutil.copytree(ROOT / "ssn_engine" / "models", folder)
    shutil.copy(_height_graph(tmp_path), folder / "height.onnx")
    meta = json.loads((folder / "model.json").read_text())
    (folder / "model.json").write_text(json.dumps({**meta, "height": "height.onnx", "proxy_internal": 32}))
    model = OnnxSSN(folder)
    assert isinstance(model.card, HeightProxy)
    mask = np.zeros((1, 256, 256), np.float32)
    mask[0, 60:200, 110:150] = 1.0
    elm = np.zeros((1, 16, 32), np.float32)
    elm[0, 10, 20] = 1.0
    shadow = model.render(mask, model.predict_ao(mask), elm)
    assert shadow.shape == (1, 256, 256) and np.isfinite(shadow).all()
    assert model.card.card_shadows(mask, elm).shape == (1, 128, 128)
    (folder / "model.json").write_text(json.dumps({**meta, "height": "height.onnx", "proxy_internal": 7}))
    from ssn_engine.methods import ModelError

    with pytest.raises(ModelError, match="proxy_internal"):
        OnnxSSN(folder)


def test_heightnet_trains_on_made_views_and_resumes(tmp_path):
    pytest.importorskip("torch")
    from training.heights import main

    mesh, _ = _scene()
    topo = meshes.topology(mesh)
    views = [view_heights(mesh, topo, yaw, pitch, 45.0) for yaw, pitch in ((0.0, 0.0), (60.0, 15.0), (120.0, 30.0))]
    data = {key: np.stack([v[key] for v in views]).astype(np.float16) for key in ("mask", "front", "back")}
    data |= {"camera": np.array([v["camera"] for v in views]), "kind": np.zeros(3, int), "pitch": np.zeros(3)}
    for split in ("train", "val"):
        np.savez(tmp_path / f"{split}_box.npz", **data)
    args = ["train", "--data", str(tmp_path), "--run", str(tmp_path / "run"), "--batch", "2", "--val-every", "2"]
    main([*args, "--steps", "2"])
    main([*args, "--steps", "4"])
    import torch

    state = torch.load(tmp_path / "run" / "last.pt", weights_only=False)
    assert state["step"] == 4 and [r["step"] for r in state["log"]] == [2, 4]
    assert all(np.isfinite(r["val"]).all() and len(r["val"]) == 4 for r in state["log"])
