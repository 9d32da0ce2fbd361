"""The out-of-source test shapes: a whole public source that gives nothing to training, tuning or the other sets.

The meshes are Alec Jacobson's *common 3D test models* (github.com/alecjacobson/common-3d-test-models): scans and
models from Stanford, Cyberware, Keenan Crane, Autodesk and others, each under its own terms (the repository's
README names each one's source; none is redistributed here, they are read from a local snapshot of the
repository). Five figures, four animals and five objects, none of them in the shared meshes, anny or the
procedural shapes; the repository's flat (2D) models, Nefertiti's scan (its up axis not worked out) and those
its snapshot lacks are left out.

``prepare`` reads each model from a git snapshot of that repository (``fetch`` brings one: a bare git
directory, read with ``git show``), turns it so that its up axis is +y, writes it as the shared meshes' PLY
layout and writes a ``manifest.csv`` of the shared meshes' columns with the split ``outsource``; with
``SSN_MESHES`` pointing at that folder, ``render --split outsource`` renders the canvas set of every shape.
"""

from __future__ import annotations

import csv
import io
import subprocess
import zipfile
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from training.data.meshes import Mesh

REPO = "alecjacobson/common-3d-test-models"
SPLIT = "outsource"
# rotations (degrees about x, then about z) that take each model's up axis to +y
UP_Z = (-90.0, 0.0)
UPRIGHT = (0.0, 0.0)


@dataclass(frozen=True)
class Model:
    """One model of the source: its id, path in the repository, kind, category, turn to +y up, source credit."""

    id: str
    path: str
    kind: str
    category: str
    turn: tuple[float, float]
    credit: str


MODELS = (
    Model("cj_beast", "data/beast.obj", "human", "creature", UPRIGHT, "Autodesk"),
    Model("cj_cow", "data/cow.obj", "animal", "cow", UPRIGHT, "Viewpoint Animation Engineering"),
    Model("cj_spot", "data/spot.obj", "animal", "cow", UPRIGHT, "Keenan Crane (CC0)"),
    Model("cj_bunny", "data/stanford-bunny.obj", "animal", "rabbit", UPRIGHT, "Stanford 3D Scanning Repository"),
    Model("cj_horse", "data/horse.zip", "animal", "horse", UP_Z, "Cyberware"),
    Model("cj_homer", "data/homer.obj", "human", "cartoon figure", UPRIGHT, "unknown (via Pierre Alliez)"),
    Model("cj_ogre", "data/ogre.obj", "human", "ogre", UPRIGHT, "Kiaran Ritchie"),
    Model("cj_cheburashka", "data/cheburashka.obj", "human", "cartoon figure", UPRIGHT, "Ilya Baran"),
    Model("cj_igea", "data/igea.ply", "human", "head", UPRIGHT, "Cyberware"),
    Model("cj_teapot", "data/teapot.obj", "object", "teapot", UPRIGHT, "Martin Newell"),
    Model("cj_fandisk", "data/fandisk.obj", "object", "machine part", UPRIGHT, "Hughes Hoppe"),
    Model("cj_rocker_arm", "data/rocker-arm.obj", "object", "machine part", UPRIGHT, "INRIA"),
    Model("cj_beetle", "data/beetle.obj", "object", "car", UPRIGHT, "Ivan Sutherland"),
    Model("cj_suzanne", "data/suzanne.obj", "object", "monkey head", UPRIGHT, "Blender"),
)


def read_obj(text: str) -> Mesh:
    """Vertices and faces of an OBJ's ``v`` and ``f`` lines (polygons split into fans, 1-based or negative
    indices, ``v/vt/vn`` references)."""
    verts: list[list[float]] = []
    faces: list[list[int]] = []
    for line in text.splitlines():
        parts = line.split()
        if not parts:
            continue
        if parts[0] == "v":
            verts.append([float(x) for x in parts[1:4]])
        elif parts[0] == "f":
            idx = [int(p.split("/")[0]) for p in parts[1:]]
            idx = [i - 1 if i > 0 else len(verts) + i for i in idx]
            faces += [[idx[0], idx[k], idx[k + 1]] for k in range(1, len(idx) - 1)]
    return Mesh(np.asarray(verts, np.float64), np.asarray(faces, np.int32))


def read_binary_ply(data: bytes) -> Mesh:
    """A little-endian binary PLY whose vertices start with float x, y, z (more float properties allowed) and
    whose faces are a ``face`` list of triangles (uchar counts) or a ``tristrips`` list (strips restart at -1)."""
    end = data.index(b"end_header\n") + len(b"end_header\n")
    header = data[:end].decode("ascii").splitlines()
    nv, props, element, list_kind = 0, [], "", ""
    counts: dict[str, int] = {}
    for line in header:
        w = line.split()
        if w[:1] == ["element"]:
            element = w[1]
            counts[element] = int(w[2])
        elif w[:1] == ["property"] and element == "vertex":
            props.append(w[1])
        elif w[:2] == ["property", "list"]:
            list_kind = element
    if any(p != "float" for p in props):
        raise ValueError("only float vertex properties are supported")
    nv = counts["vertex"]
    v = np.frombuffer(data, "<f4", nv * len(props), end).reshape(nv, len(props))[:, :3]
    offset = end + 4 * nv * len(props)
    if list_kind == "face":
        f = np.frombuffer(data, [("n", "u1"), ("i", "<i4", 3)], counts["face"], offset)
        if np.any(f["n"] != 3):
            raise ValueError("only triangle faces are supported")
        return Mesh(v.astype(np.float64), f["i"].astype(np.int32))
    if list_kind == "tristrips":
        rest = np.frombuffer(data, "<i4", offset=offset)
        faces = []
        pos = 0
        for _ in range(counts["tristrips"]):
            n = int(rest[pos])
            strip = rest[pos + 1 : pos + 1 + n]
            pos += 1 + n
            for run in np.split(strip, np.flatnonzero(strip < 0)):
                run = run[run >= 0]
                for k in range(len(run) - 2):
                    a, b, c = run[k : k + 3]
                    faces.append((a, b, c) if k % 2 == 0 else (b, a, c))
        return Mesh(v.astype(np.float64), np.asarray(faces, np.int32))
    raise ValueError(f"unsupported PLY faces: {list_kind!r}")


def read_model(git_dir: Path, model: Model) -> Mesh:
    """The model's mesh from the snapshot's HEAD, turned so that its up axis is +y."""
    data = subprocess.run(
        ["git", "--git-dir", str(git_dir), "show", f"HEAD:{model.path}"], check=True, capture_output=True
    ).stdout
    if model.path.endswith(".zip"):
        with zipfile.ZipFile(io.BytesIO(data)) as z:
            name = next(n for n in z.namelist() if n.endswith(".ply") and not n.startswith("__MACOSX"))
            data = z.read(name)
    mesh = read_obj(data.decode("utf-8", "replace")) if model.path.endswith(".obj") else read_binary_ply(data)
    return Mesh(turned(mesh.vertices, *model.turn), mesh.faces)


def turned(vertices: np.ndarray, about_x: float, about_z: float) -> np.ndarray:
    """Vertices turned about x, then about z (degrees, right-handed)."""
    a, b = np.radians(about_x), np.radians(about_z)
    rx = np.array([[1, 0, 0], [0, np.cos(a), -np.sin(a)], [0, np.sin(a), np.cos(a)]])
    rz = np.array([[np.cos(b), -np.sin(b), 0], [np.sin(b), np.cos(b), 0], [0, 0, 1]])
    return vertices @ (rz @ rx).T


def write_ply(path: Path, mesh: Mesh) -> None:
    """The shared meshes' PLY layout: float x, y, z; uchar 3 + int32 triangles."""
    header = (
        f"ply\nformat binary_little_endian 1.0\nelement vertex {len(mesh.vertices)}\n"
        "property float x\nproperty float y\nproperty float z\n"
        f"element face {len(mesh.faces)}\nproperty list uchar int vertex_indices\nend_header\n"
    )
    faces = np.zeros(len(mesh.faces), [("n", "u1"), ("i", "<i4", 3)])
    faces["n"], faces["i"] = 3, mesh.faces
    path.write_bytes(header.encode("ascii") + mesh.vertices.astype("<f4").tobytes() + faces.tobytes())


def prepare(git_dir: Path, out: Path, models: tuple[Model, ...] = MODELS, log=print) -> list[dict[str, str]]:
    """Write each of ``models``' PLY and the folder's ``manifest.csv`` (the shared meshes' columns)."""
    out.mkdir(parents=True, exist_ok=True)
    revision = subprocess.run(
        ["git", "--git-dir", str(git_dir), "rev-parse", "HEAD"], check=True, capture_output=True, text=True
    ).stdout.strip()
    rows = []
    for model in models:
        mesh = read_model(git_dir, model)
        file = f"{model.id}.ply"
        write_ply(out / file, mesh)
        rows.append(
            {
                "id": model.id,
                "file": file,
                "category": model.category,
                "kind": model.kind,
                "source_repo": REPO,
                "source_path": f"{model.path}@{revision[:12]}",
                "licence": "the original source's terms (research test model; not redistributed)",
                "attribution": model.credit,
                "vertices": str(len(mesh.vertices)),
                "faces": str(len(mesh.faces)),
                "split": SPLIT,
            }
        )
        log(f"{model.id}: {len(mesh.vertices)} vertices, {len(mesh.faces)} faces")
    with open(out / "manifest.csv", "w", newline="") as fh:
        writer = csv.DictWriter(fh, fieldnames=list(rows[0]))
        writer.writeheader()
        writer.writerows(rows)
    return rows
