"""Procedural shapes and anny humans: reproducible from their recorded parameters, sane geometry."""

from __future__ import annotations

import numpy as np
import pytest

from training.data import meshes, procedural, sources
from training.data import render_bases as rb


def test_procedural_items_are_reproducible_and_split_by_shape():
    items = procedural.procedural_items(30, seed=3)
    assert len({it.id for it in items}) == 30
    assert {it.split for it in items} == {"train", "val", "test"}
    for it in items[:12]:
        a, b = sources.build_mesh(it), sources.build_mesh(it)
        np.testing.assert_array_equal(a.vertices, b.vertices)
        lo, hi = a.vertices.min(0), a.vertices.max(0)
        assert abs(np.linalg.norm(hi - lo) - 1) < 1e-9 and abs(lo[1]) < 1e-12
        assert abs(lo[0] + hi[0]) < 1e-9 and abs(lo[2] + hi[2]) < 1e-9


def test_primitives_are_closed_and_outward():
    for mesh in (
        procedural.box((1, 2, 3)),
        procedural.cylinder(0.3, 1.0),
        procedural.uv_sphere(0.5),
        procedural.torus(0.4, 0.1),
    ):
        topo = meshes.topology(mesh)
        counts = np.diff(topo.ptr)
        assert np.all(counts == 2)  # closed 2-manifold
        # consistently oriented: every edge is used once in each direction
        sums = np.add.reduceat(topo.inc_dir.astype(int), topo.ptr[:-1])
        assert np.all(sums == 0)
        n = meshes.face_normals(mesh.vertices, mesh.faces)
        centroid = mesh.vertices[mesh.faces].mean(1) - mesh.vertices.mean(0)
        volume = (n * mesh.vertices[mesh.faces[:, 0]]).sum() / 6
        assert volume > 0  # outward normals
        del centroid


def test_torus_shadow_has_a_hole():
    mesh = meshes.normalise(procedural.torus(0.4, 0.08, upright=False))  # lying flat: a ring on the ground
    cam = rb.view_camera(mesh.vertices, 96, 45.0, 30.0)
    from helpers import hard_shadow, light_direction

    occ = hard_shadow(mesh, cam, light_direction(cam, 89.0, 0.0)).astype(bool)
    g, _ = cam.ground_points()
    d = np.hypot(g[..., 0], g[..., 2])
    r = mesh.vertices[:, 0].max()
    assert occ[(d > 0.85 * r) & (d < 0.95 * r)].all() and not occ[d < 0.5 * r].any()


def test_anny_humans_are_reproducible_people():
    pytest.importorskip("anny")
    from training.data import humans

    items = humans.human_items(3, seed=1)
    assert {it.kind for it in items} == {"human"}
    assert items[0].params == humans.human_items(1, seed=1)[0].params
    mesh = sources.build_mesh(items[0])
    again = sources.build_mesh(items[0])
    np.testing.assert_array_equal(mesh.vertices, again.vertices)
    lo, hi = mesh.vertices.min(0), mesh.vertices.max(0)
    assert hi[1] - lo[1] > 0.7  # taller than wide or deep
    for it in items:
        for key, value in it.params["angles"].items():
            role = key[:-2] if key.endswith(("_L", "_R")) else key
            lo_lim, hi_lim = humans.LIMITS[role]
            assert lo_lim <= value <= hi_lim
