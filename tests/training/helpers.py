"""Shared helpers for the training-data tests: single-direction hard shadows and ELM directions."""

from __future__ import annotations

import numpy as np

from training.data import meshes
from training.data import render_bases as rb


def hard_shadow(mesh: meshes.Mesh, camera, w) -> np.ndarray:
    """Occlusion (N, N) 0/1 of the ground points seen by ``camera`` from the single world direction w."""
    rows = rb.ground_rows(camera)
    topo = meshes.topology(mesh)
    dirs = np.ascontiguousarray(np.asarray(w, float).reshape(1, 1, 3))
    out = rb.occlusion_counts(
        *rb.kernel_args(mesh.vertices, meshes.face_normals(mesh.vertices, mesh.faces), topo, rows, dirs, camera.n)
    )
    return out[0]


def light_direction(camera, elevation_deg: float, azimuth_deg: float) -> np.ndarray:
    """World direction of ELM elevation/azimuth (conventions: azimuth from forward, positive right)."""
    e, a = np.radians(elevation_deg), np.radians(azimuth_deg)
    return camera.to_world(np.array([np.cos(e) * np.sin(a), np.sin(e), np.cos(e) * np.cos(a)]))
