"""Truth renders at canvas scale: a disk light's shadow s, the object's mask and the true camera.

The canvas (W x H, W >= H) is the top H rows of a square W x W frame of the conventions' camera
(:class:`ssn_engine.camera.Camera` looking at the AABB centre from distance 2), with a focal length chosen
so that the object spans ``OBJECT_SHARE`` of the canvas height (or ``MAX_WIDTH_SHARE`` of its width, when
that is smaller) and a lens shift putting its top on row round(``TOP_SHARE`` * H). The shadow comes from the
training renderer's contour-edge kernel (:mod:`training.data.render_bases`), one direction at a time, each
weighted by its cosine to the zenith: s = 1 - E / E0 over the disk's sampled directions.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from ssn_engine.camera import Camera, fov_from_focal
from training.data import meshes
from training.data import render_bases as rb

OBJECT_SHARE = 0.42  # the object's height over the canvas height
MAX_WIDTH_SHARE = 0.6  # a wide object is made smaller instead, so that it fits across the canvas
TOP_SHARE = 0.2  # the object's top row over the canvas height
MASK_SAMPLES = 4  # point samples per pixel side for the mask
CHUNK = 32  # directions rendered at once (memory: CHUNK * W * W bytes)


@dataclass(frozen=True)
class CanvasCamera:
    """A canvas of ``width`` x ``height`` and the square frame camera whose top rows it is.

    ``fov`` is the canvas's vertical field of view (degrees, over ``height`` rows) and ``horizon`` its
    horizon row (conventions, "Camera input"), both what ``ssn-shadow render --horizon --fov`` takes.
    """

    width: int
    height: int
    camera: Camera

    @property
    def focal(self) -> float:
        return float(self.camera.focal)

    @property
    def fov(self) -> float:
        return fov_from_focal(self.height, self.focal)

    @property
    def horizon(self) -> float:
        return float(self.camera.horizon)


def canvas_camera(vertices: np.ndarray, width: int, height: int, pitch: float) -> CanvasCamera:
    """The canvas camera for normalised, yawed ``vertices`` seen from ``pitch`` degrees down.

    The projected height and width of the object are proportional to the focal length (the camera's
    position does not depend on it), so one projection at a unit focal length fixes it exactly.
    """
    if width < height:
        raise ValueError(f"the canvas must be at least as wide as it is high, got {width} x {height}")
    centre = 0.5 * (vertices[:, 1].min() + vertices[:, 1].max())
    unit = Camera(width, centre, fov=2 * np.degrees(np.arctan(0.5 * width)), pitch=pitch)  # focal length 1
    uv = unit.project(vertices)
    span_rows = float(np.ptp(uv[:, 1]))
    span_cols = float(np.ptp(uv[:, 0]))
    focal = min(OBJECT_SHARE * height / span_rows, MAX_WIDTH_SHARE * width / span_cols)
    cam = Camera(width, centre, fov=fov_from_focal(width, focal), pitch=pitch)
    cam.shift = round(TOP_SHARE * height) - float(cam.project(vertices)[:, 1].min())
    return CanvasCamera(width, height, cam)


def disk_shadow(
    vertices: np.ndarray, faces: np.ndarray, topo: meshes.Topology, canvas: CanvasCamera, directions: np.ndarray
) -> np.ndarray:
    """s = 1 - E / E0 over the canvas for a light made of ``directions`` (S, 3, world, each the same solid
    angle, pointing up): each direction's hard shadow weighted by its cosine to the zenith. (H, W) float32."""
    directions = np.asarray(directions, np.float64)
    if np.any(directions[:, 1] <= 0):
        raise ValueError("every light direction must point above the horizon")
    weights = directions[:, 1] / directions[:, 1].sum()
    n = canvas.width
    rows = rb.ground_rows(canvas.camera)
    normals = meshes.face_normals(vertices, faces)
    s = np.zeros((n, n))
    for start in range(0, len(directions), CHUNK):
        dirs = np.ascontiguousarray(directions[start : start + CHUNK, None, :])
        counts = rb.occlusion_counts(*rb.kernel_args(vertices, normals, topo, rows, dirs, n))
        s += rb.weighted_sum(counts, weights[start : start + CHUNK])
    return np.clip(s[: canvas.height], 0.0, 1.0).astype(np.float32)


def canvas_mask(vertices: np.ndarray, faces: np.ndarray, topo: meshes.Topology, canvas: CanvasCamera) -> np.ndarray:
    """The object's coverage of every canvas pixel, (H, W) float32 in [0, 1]."""
    return rb.mask_coverage(vertices, faces, topo, canvas.camera, MASK_SAMPLES)[: canvas.height]


__all__ = ["CanvasCamera", "OBJECT_SHARE", "canvas_camera", "canvas_mask", "disk_shadow"]
