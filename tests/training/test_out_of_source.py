"""The out-of-source test shapes (training.canvas_eval.out_of_source): read from a snapshot of their repository,
turned upright, written as the shared meshes' PLY with a manifest of the shared meshes' columns."""

from __future__ import annotations

import csv
import subprocess

import numpy as np

from training.canvas_eval import cases
from training.canvas_eval import out_of_source as oos
from training.data import meshes, sources
from training.data.items import Item

TETRA = """# a tetrahedron standing on its base, +z up; a quad for the base, v/vt/vn references and negative indices
v 0 0 0
v 1 0 0
v 1 1 0
v 0 1 0
v 0.5 0.5 2
f 1/1/1 4/2/1 3/3/1 2/4/1
f -5 -4 -1
f 2//1 3//1 5//1
f 3 4 5
f 4 1 5
"""


def test_an_obj_s_polygons_become_triangles_with_their_vertices():
    mesh = oos.read_obj(TETRA)
    assert mesh.vertices.shape == (5, 3) and mesh.faces.shape == (6, 3)
    np.testing.assert_array_equal(mesh.faces[:2], [[0, 3, 2], [0, 2, 1]])  # the quad as a fan
    np.testing.assert_array_equal(mesh.faces[2], [0, 1, 4])  # negative indices count back from the last vertex


def test_a_ply_of_triangle_strips_keeps_each_triangle_s_winding():
    header = (
        b"ply\nformat binary_little_endian 1.0\nelement vertex 5\nproperty float x\nproperty float y\n"
        b"property float z\nelement tristrips 1\nproperty list int int vertex_indices\nend_header\n"
    )
    verts = np.arange(15, dtype="<f4").tobytes()
    strip = np.array([7, 0, 1, 2, 3, -1, 2, 3, 4], "<i4")  # 0 1 2 3 (two triangles), restart, 2 3 4
    strip[0] = len(strip) - 1
    mesh = oos.read_binary_ply(header + verts + strip.tobytes())
    np.testing.assert_array_equal(mesh.faces, [[0, 1, 2], [2, 1, 3], [2, 3, 4]])


def test_prepare_writes_upright_meshes_and_a_manifest(tmp_path):
    repo = tmp_path / "src"
    (repo / "data").mkdir(parents=True)
    (repo / "data" / "tetra.obj").write_text(TETRA)
    for cmd in (["init", "-q"], ["add", "."], ["-c", "user.name=t", "-c", "user.email=t@t", "commit", "-qm", "m"]):
        subprocess.run(["git", *cmd], cwd=repo, check=True)
    model = oos.Model("cj_tetra", "data/tetra.obj", "object", "tetrahedron", oos.UP_Z, "nobody")
    rows = oos.prepare(repo / ".git", tmp_path / "out", (model,), log=lambda *_: None)
    with open(tmp_path / "out" / "manifest.csv", newline="") as fh:
        written = list(csv.DictReader(fh))
    assert written == rows and list(written[0]) == list(meshes.read_manifest()[0])  # the shared meshes' columns
    assert written[0]["split"] == oos.SPLIT and written[0]["source_repo"] == oos.REPO
    mesh = meshes.read_ply(tmp_path / "out" / written[0]["file"])
    assert mesh.faces.shape == (6, 3)
    assert np.argmax(np.ptp(mesh.vertices, axis=0)) == 1  # its apex, +z in the file, is up (+y)
    assert mesh.vertices[4, 1] == 2.0


def test_the_out_of_source_split_takes_every_shape_of_its_folder():
    items = [Item(f"cj_{k}", oos.SPLIT, kind, "same", "mesh") for k, kind in enumerate(["human"] * 5 + ["object"] * 9)]
    picked = cases.pick_shapes(items + sources.manifest_items(), quota=None, split=oos.SPLIT)
    assert sorted(it.id for it in picked) == sorted(it.id for it in items)
    assert len(cases.pick_shapes(items, split=oos.SPLIT)) == 2 + 7  # the in-source sets' quota would drop some


def test_no_out_of_source_shape_is_a_shared_mesh():
    """The source gives nothing to training: none of its files or names is among the shared meshes."""
    shared = meshes.read_manifest()
    assert not {m.id for m in oos.MODELS} & {r["id"] for r in shared}
    assert oos.REPO not in {r["source_repo"] for r in shared}
