"""Triangle meshes: reading the shared PLY files, the conventions' normalisation, yaw, topology.

Normalisation (``docs/conventions.md``): scale uniformly so that the
axis-aligned bounding box (AABB) diagonal is 1, then move the AABB's lowest y
to 0 and its centre to x = z = 0. A view then turns the object about the y
axis by its yaw (right-handed: +90 degrees takes +x to -z).
"""

from __future__ import annotations

import csv
import os
from dataclasses import dataclass
from pathlib import Path

import numpy as np

SHARED_MESHES = Path(os.environ.get("SSN_MESHES", Path(__file__).resolve().parents[3] / "shared" / "meshes"))


@dataclass
class Mesh:
    """Vertices (V, 3) float64 and triangles (F, 3) int32."""

    vertices: np.ndarray
    faces: np.ndarray


@dataclass
class Topology:
    """Undirected edges and their face incidences (CSR), for the contour-edge rasteriser.

    ``edges`` (E, 2) int32 with edges[:, 0] < edges[:, 1]; the incidences of
    edge e are ``inc_face[ptr[e]:ptr[e + 1]]`` with ``inc_dir`` +1 where the
    face runs the edge from edges[e, 0] to edges[e, 1] and -1 otherwise.
    """

    edges: np.ndarray
    ptr: np.ndarray
    inc_face: np.ndarray
    inc_dir: np.ndarray


def read_ply(path: str | Path) -> Mesh:
    """Read the binary little-endian PLY layout of ``shared/meshes`` (float xyz, uchar 3 + int32 faces)."""
    b = Path(path).read_bytes()
    end = b.index(b"end_header\n") + 11
    hdr = b[:end].decode("ascii").split()
    nv = int(hdr[hdr.index("vertex") + 1])
    nf = int(hdr[hdr.index("face") + 1])
    v = np.frombuffer(b, "<f4", nv * 3, end).reshape(nv, 3)
    f = np.frombuffer(b, [("n", "u1"), ("i", "<i4", 3)], nf, end + 12 * nv)
    if np.any(f["n"] != 3):
        raise ValueError(f"{path}: only triangles are supported")
    return Mesh(v.astype(np.float64), f["i"].astype(np.int32))


def read_manifest(root: Path = SHARED_MESHES) -> list[dict[str, str]]:
    """The rows of ``manifest.csv`` in file order."""
    with open(root / "manifest.csv", newline="") as fh:
        return list(csv.DictReader(fh))


def clean(mesh: Mesh) -> Mesh:
    """Drop faces with repeated vertex indices and vertices no face uses."""
    f = mesh.faces
    ok = (f[:, 0] != f[:, 1]) & (f[:, 1] != f[:, 2]) & (f[:, 2] != f[:, 0])
    f = f[ok]
    used, inverse = np.unique(f, return_inverse=True)
    return Mesh(mesh.vertices[used], inverse.reshape(-1, 3).astype(np.int32))


def normalise(mesh: Mesh) -> Mesh:
    """Scale to an AABB diagonal of 1, lowest y to 0, AABB centre to x = z = 0."""
    v = mesh.vertices
    lo, hi = v.min(axis=0), v.max(axis=0)
    diag = float(np.linalg.norm(hi - lo))
    if diag <= 0:
        raise ValueError("degenerate mesh")
    v = (v - np.array([(lo[0] + hi[0]) / 2, lo[1], (lo[2] + hi[2]) / 2])) / diag
    return Mesh(v, mesh.faces)


def yawed(vertices: np.ndarray, yaw_deg: float) -> np.ndarray:
    """Turn vertices about the y axis by ``yaw_deg`` (right-handed, +90 maps +x to -z)."""
    a = np.radians(yaw_deg)
    c, s = np.cos(a), np.sin(a)
    rot = np.array([[c, 0.0, s], [0.0, 1.0, 0.0], [-s, 0.0, c]])
    return vertices @ rot.T


def topology(mesh: Mesh) -> Topology:
    """Undirected edges with their face incidences."""
    f = mesh.faces.astype(np.int64)
    a = f.reshape(-1)
    b = f[:, [1, 2, 0]].reshape(-1)
    lo, hi = np.minimum(a, b), np.maximum(a, b)
    direction = np.where(a < b, 1, -1).astype(np.int8)
    key = lo * (int(hi.max()) + 1) + hi
    order = np.argsort(key, kind="stable")
    key_sorted = key[order]
    start = np.flatnonzero(np.r_[True, key_sorted[1:] != key_sorted[:-1]])
    ptr = np.r_[start, key_sorted.size].astype(np.int64)
    edges = np.stack([lo[order][start], hi[order][start]], axis=1).astype(np.int32)
    inc_face = (order // 3).astype(np.int32)
    return Topology(edges, ptr, inc_face, direction[order])


def face_normals(vertices: np.ndarray, faces: np.ndarray) -> np.ndarray:
    """Unnormalised face normals cross(b - a, c - a), shape (F, 3)."""
    a = vertices[faces[:, 0]]
    return np.cross(vertices[faces[:, 1]] - a, vertices[faces[:, 2]] - a)
