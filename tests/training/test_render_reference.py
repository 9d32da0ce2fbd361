"""The fast renderer against brute-force ray casting, and the ELM orientation conventions end to end."""

from __future__ import annotations

import numpy as np
import pytest

from ssn_engine.hemisphere import render_light_map, soft_shadow, stratified_directions
from ssn_engine.host_kit.light_map import LightMap
from training.data import meshes, procedural, sources
from training.data import render_bases as rb
from training.data.raycast import ray_hits
from training.data.spans import quantise_counts


def _shared_mesh(uid: str) -> meshes.Mesh:
    if not (meshes.SHARED_MESHES / "manifest.csv").exists():
        pytest.skip("shared meshes not available")
    item = next(it for it in sources.manifest_items() if it.id == uid)
    return sources.build_mesh(item)


@pytest.mark.parametrize(
    "uid,yaw,pitch", [("capod_chair_01", 45.0, 15.0), ("ycb_banana", -90.0, 30.0), ("capod_spider_01", 0.0, 0.0)]
)
def test_bases_agree_with_brute_force_ray_casting(uid, yaw, pitch):
    mesh = _shared_mesh(uid)
    n, hb, s = 96, 16, 16
    rend = rb.render_view(mesh, meshes.topology(mesh), yaw, pitch, 45.0, n, hb, s, np.random.default_rng(3))
    dirs = rend.camera.to_world(stratified_directions(hb, s, np.random.default_rng(3)))
    g, down = rend.camera.ground_points()
    v = meshes.yawed(mesh.vertices, yaw)
    rng = np.random.default_rng(0)
    checked = mismatched = 0
    for _ in range(12):
        ti, tj = rng.integers(hb), rng.integers(2 * hb)
        pix = np.argwhere(down)[rng.integers(down.sum(), size=30)]
        shadowed = np.argwhere(rend.counts[ti, tj] > 0)
        if len(shadowed):
            pix = np.concatenate([pix, shadowed[rng.integers(len(shadowed), size=30)]])
        origins = g[pix[:, 0], pix[:, 1]]
        hits = np.zeros(len(pix), int)
        for k in range(s):
            hits += ray_hits(origins, np.broadcast_to(dirs[ti, tj, k], origins.shape), v, mesh.faces)
        checked += len(pix)
        mismatched += int((hits != rend.counts[ti, tj][pix[:, 0], pix[:, 1]]).sum())
    assert checked > 500
    assert mismatched <= checked // 1000  # a ray grazing an edge may round either way


def test_mask_agrees_with_brute_force_ray_casting():
    mesh = _shared_mesh("capod_chair_01")
    n, ss = 48, 4
    v = meshes.yawed(mesh.vertices, 45.0)
    cam = rb.view_camera(v, n, 45.0, 15.0)
    mask = rb.mask_coverage(v, mesh.faces, meshes.topology(mesh), cam, ss)
    sub = (np.arange(n * ss) + 0.5) / ss
    cols, rows = np.meshgrid(sub, sub)
    rays = (
        cam.view
        + ((cols - 0.5 * n) / cam.focal)[..., None] * np.array([1.0, 0, 0])
        - ((rows - cam.shift - 0.5 * n) / cam.focal)[..., None] * cam.up
    )
    hits = ray_hits(np.broadcast_to(cam.centre, rays.shape).reshape(-1, 3), rays.reshape(-1, 3), v, mesh.faces)
    brute = hits.reshape(n, ss, n, ss).mean(axis=(1, 3))
    assert np.abs(brute - mask).max() <= 1.0 / ss**2 + 1e-6  # at most one sub-sample on an edge differs
    assert mask.sum() > 50


def _shadow_of(mesh, u: float, v: float) -> tuple[np.ndarray, np.ndarray]:
    hb = 16
    rend = rb.render_view(mesh, meshes.topology(mesh), 0.0, 20.0, 45.0, 96, hb, 16, np.random.default_rng(0))
    lm = LightMap()
    lm.add(u, v, 0.002, 1.0)
    occ = quantise_counts(rend.counts, 16).astype(np.float32) / 255
    return soft_shadow(occ, render_light_map(lm, hb)), rend.mask


def _centroid(img: np.ndarray) -> np.ndarray:
    rows, cols = np.indices(img.shape)
    return np.array([(img * cols).sum(), (img * rows).sum()]) / img.sum()


def test_light_right_of_centre_casts_the_shadow_left():
    mesh = meshes.normalise(procedural.box((0.2, 1.0, 0.2)))
    s, mask = _shadow_of(mesh, 0.75, 0.5)  # azimuth +90: to the camera's right
    (sx, sy), (mx, _) = _centroid(s), _centroid(mask)
    assert sx < mx - 5 and abs(sy - np.argwhere(mask > 0)[:, 0].max()) < 10


def test_light_at_centre_column_casts_the_shadow_down_the_frame():
    mesh = meshes.normalise(procedural.box((0.2, 1.0, 0.2)))
    s, mask = _shadow_of(mesh, 0.5, 0.5)  # straight ahead, behind the object
    (sx, sy), (mx, _) = _centroid(s), _centroid(mask)
    assert abs(sx - mx) < 1.0 and sy > np.argwhere(mask > 0)[:, 0].max()
    s_back, _ = _shadow_of(mesh, 0.0, 0.5)  # behind the camera: the shadow goes away, up the frame
    assert _centroid(s_back)[1] < sy


def test_all_zero_elm_gives_no_shadow():
    mesh = meshes.normalise(procedural.box((0.3, 0.5, 0.3)))
    rend = rb.render_view(mesh, meshes.topology(mesh), 0.0, 20.0, 45.0, 32, 16, 16, np.random.default_rng(0))
    assert not soft_shadow(rend.counts.astype(np.float32) / 16, np.zeros((16, 32))).any()
