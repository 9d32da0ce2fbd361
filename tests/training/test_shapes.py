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


def test_people_off_their_feet_are_their_own_source_and_leave_the_standing_ones_as_they_were():
    """``anny_poses``: running, sitting, crouching, kneeling and lying people, reproducible; a lying person is long
    and low, a crouching or kneeling one deeper for its height than one standing; the ``anny`` source's people
    are the ones its sets were made of."""
    pytest.importorskip("anny")
    from training.data import humans

    standing = humans.human_items(6, seed=1)
    assert [it.params["pose"] for it in standing] == [
        "standing", "standing", "arm_out", "walking", "arm_out", "arms_raised"
    ]  # fmt: skip
    assert standing[1].params["angles"]["hip_x_L"] == pytest.approx(-5.7466, abs=1e-4)
    posed = humans.human_items(40, seed=5, poses=humans.MORE_POSES)
    assert {it.source for it in posed} == {"anny_poses"} and {it.kind for it in posed} == {"human"}
    assert {it.params["pose"] for it in posed} == set(humans.MORE_POSES)
    assert not {it.id for it in posed} & {it.id for it in humans.human_items(40, seed=5)}
    # A set made without naming its sources is made of the ones every set was made of before these were added.
    default = sources.all_items(n_procedural=4, n_humans=4, seed=5, n_quadrupeds=4)
    assert {it.source for it in default} == {"mesh", "procedural", "anny"}
    upright = np.ptp(sources.build_mesh(standing[0]).vertices, axis=0)
    assert upright[1] > 3.0 * upright[2]  # standing: over three times as tall as deep (front to back)
    for pose in ("lying", "crouching", "kneeling"):
        it = next(it for it in posed if it.params["pose"] == pose)
        mesh = sources.build_mesh(it)
        np.testing.assert_array_equal(mesh.vertices, sources.build_mesh(it).vertices)
        ext = np.ptp(mesh.vertices, axis=0)
        if pose == "lying":
            assert ext[1] < 0.45 * max(ext[0], ext[2])
        else:
            assert ext[1] < 2.7 * ext[2]


def test_procedural_animals_stand_in_their_pose_and_rebuild_from_their_seed():
    """Every pose family, reproducible; a lying animal is low and long, a standing one's legs leave light under
    its body, a grazing one's head reaches down to the ground, a sitting one rises from the rump."""
    from training.data import quadrupeds

    items = quadrupeds.quadruped_items(50, seed=2)
    assert {it.kind for it in items} == {"animal"} and {it.split for it in items} == {"train", "val", "test"}
    for split in ("train", "val", "test"):
        assert {it.params["pose"] for it in items if it.split == split} == set(quadrupeds.POSES)
    assert [it.id for it in sources.all_items(("quadruped",), seed=2, n_quadrupeds=50)] == sorted(
        (it.id for it in items), key=lambda i: (sources.stable_hash(i), i)
    )
    by_pose: dict[str, list] = {}
    for it in items:
        mesh = sources.build_mesh(it)
        np.testing.assert_array_equal(mesh.vertices, sources.build_mesh(it).vertices)
        lo, hi = mesh.vertices.min(0), mesh.vertices.max(0)
        assert abs(np.linalg.norm(hi - lo) - 1) < 1e-9 and abs(lo[1]) < 1e-12
        by_pose.setdefault(it.params["pose"], []).append(mesh)

    def height_over_length(mesh):
        ext = np.ptp(mesh.vertices, axis=0)
        return ext[1] / ext[0]

    def light_under_the_belly(mesh):  # the share of a thin slab at a fifth of the height, under the body, left empty
        v, x = mesh.vertices, mesh.vertices[:, 0]
        mid = np.abs(x - 0.5 * (x.min() + x.max())) < 0.1 * np.ptp(x)
        return float(np.mean(v[mid, 1] > 0.2 * v[:, 1].max()))

    lying = np.median([height_over_length(m) for m in by_pose["lying"]])
    standing = np.median([height_over_length(m) for m in by_pose["standing"]])
    assert lying < 0.75 * standing
    assert np.median([light_under_the_belly(m) for m in by_pose["standing"]]) > 0.9
    for mesh in by_pose["grazing"]:  # the head, the part farthest forward, comes down near the ground
        v = mesh.vertices
        front = v[v[:, 0] > v[:, 0].max() - 0.05]
        assert front[:, 1].min() < 0.5 * v[:, 1].max()
    for mesh in by_pose["sitting"]:  # the rump (or the tail behind it) low, the withers high
        v = mesh.vertices
        assert v[v[:, 0] < v[:, 0].min() + 0.1, 1].min() < 0.2 * v[:, 1].max()


def test_grounded_objects_lay_their_flat_parts_on_the_ground_and_rebuild_from_their_seed():
    """Every family in every split, reproducible, a source only when named; the cord, the mat, the legs and the
    litter lie on the ground out beyond the body: the low parts reach farther than the raised ones."""
    from training.data import grounded

    items = grounded.grounded_items(80, seed=3)
    assert {it.source for it in items} == {"grounded"} and {it.split for it in items} == {"train", "val", "test"}
    for split in ("train", "val", "test"):
        assert {it.params["kind"] for it in items if it.split == split} == set(grounded.KINDS)
    default = sources.all_items(n_procedural=4, n_humans=4, seed=3, n_grounded=8)
    assert "grounded" not in {it.source for it in default}
    assert len(sources.all_items(("grounded",), seed=3, n_grounded=8)) == 8
    for kind in grounded.KINDS:
        reach = []
        for it in [it for it in items if it.params["kind"] == kind][:6]:
            mesh = sources.build_mesh(it)
            np.testing.assert_array_equal(mesh.vertices, sources.build_mesh(it).vertices)
            v = mesh.vertices
            lo, hi = v.min(0), v.max(0)
            assert abs(np.linalg.norm(hi - lo) - 1) < 1e-9 and abs(lo[1]) < 1e-12
            low = v[:, 1] < 0.25 * hi[1]
            centre = (v[~low].min(0) + v[~low].max(0)) / 2  # the raised parts' middle
            out = np.hypot(v[:, 0] - centre[0], v[:, 2] - centre[2])
            reach.append(out[low].max() / out[~low].max())
        assert np.median(reach) > 1.1, (kind, reach)  # a high spider's knees reach out up to 0.6 of its feet


def test_procedural_animals_cast_the_shadow_of_a_solid():
    """The union of closed, outward parts: each part a 2-manifold, and a sun overhead casts no shadow wider than
    the animal's own footprint."""
    from helpers import hard_shadow, light_direction

    from training.data import quadrupeds

    part = quadrupeds.ellipsoid((0, 0, 0), (1, 0.5, 0.2), 0.2, 0.1)
    topo = meshes.topology(part)
    assert np.all(np.diff(topo.ptr) == 2) and np.all(np.add.reduceat(topo.inc_dir.astype(int), topo.ptr[:-1]) == 0)
    n = meshes.face_normals(part.vertices, part.faces)
    assert (n * part.vertices[part.faces[:, 0]]).sum() / 6 > 0
    mesh = meshes.normalise(quadrupeds.generate("standing", 5))
    cam = rb.view_camera(mesh.vertices, 96, 45.0, 30.0)
    occ = hard_shadow(mesh, cam, light_direction(cam, 89.9, 0.0)).astype(bool)
    g, _ = cam.ground_points()
    lo, hi = mesh.vertices.min(0), mesh.vertices.max(0)
    inside = (g[..., 0] >= lo[0] - 0.01) & (g[..., 0] <= hi[0] + 0.01) & (g[..., 2] >= lo[2] - 0.01)
    inside &= g[..., 2] <= hi[2] + 0.01
    assert occ.any() and not (occ & ~inside).any()
