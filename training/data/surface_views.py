"""The surface model's data: each view's mask, camera input and the pixel heights of the surfaces it shows.

A covered pixel's *pixel height* is how many rows below it the image of its visible surface point's foot lies:
the point's ground projection straight below it, projected back into the frame (Sheng et al.'s pixel height, SSG
/ PixHt-Lab). With the camera it places each pixel's surface in 3D, which the outline alone does not tell: the
hard-light tracer (:mod:`ssn_engine.hard_light`) starts each pixel's segment there. The pixel height of the far
surface (the last face the pixel's ray meets) says where that segment ends: how deep the object is there.

Each view's camera is drawn exactly as ``training.make_dataset`` draws it; its mask is the dataset's coverage at
N = 256 resampled to R; the surface is the mesh's nearest face at each pixel centre of R. ``python -m
training.surface make`` writes a split's views to one npz file (:func:`make`): masks bit-packed at 0.5 coverage,
heights and depths (the visible surface's pixel height less the far one's) as 8 bits (``HEIGHT_STEPS`` a frame)
on the covered pixels only, so that a split travels small.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np

from ssn_engine.camera import Camera
from ssn_engine.frames import nearest_fill, resample_frames

from ..canvas_eval.oracle import foot_image_rows, surface_depths
from . import meshes
from .camera_views import split_views, unpacked_masks
from .items import stable_hash
from .meshes import yawed
from .render_bases import mask_coverage, view_camera
from .sources import DEFAULT_SOURCES

__all__ = ["HEIGHT_STEPS", "R", "load", "make", "pixel_heights", "save", "stretched", "view_record"]

FRAME = 256  # the frame the masks are covered at (the engine's N)
R = 128
HEIGHT_STEPS = 2 * R  # an 8-bit pixel height counts half rows of R: up to 127.5 rows (a frame)


def pixel_heights(vertices: np.ndarray, faces: np.ndarray, cam: Camera) -> tuple[np.ndarray, np.ndarray]:
    """(n, n) each, the pixel heights (rows of ``cam``'s frame) at each pixel centre of ``cam``'s frame of the
    mesh's visible surface and of its far surface (the last face the pixel's ray meets: where the object's depth
    there ends); nan where no face is."""
    n = cam.n
    front, back = surface_depths(vertices, faces, cam, n, n, 1)
    yy, xx = np.nonzero(np.isfinite(front))
    rays = cam.rays(xx + 0.5, yy + 0.5)
    out = []
    for depth in (front, back):
        heights = np.full((n, n), np.nan, np.float32)
        heights[yy, xx] = foot_image_rows(cam, rays, depth[yy, xx]) - (yy + 0.5)
        out.append(heights)
    return out[0], out[1]


def view_record(mesh: meshes.Mesh, topo: meshes.Topology, yaw: float, pitch: float, fov: float) -> dict:
    """One view at R: its mask (coverage), camera input (horizon row, focal length), and the pixel heights (rows)
    of its visible and far surfaces (:func:`pixel_heights`)."""
    v = np.ascontiguousarray(yawed(mesh.vertices, yaw))
    cam = view_camera(v, FRAME, fov, pitch)
    frame_mask = mask_coverage(v, mesh.faces, topo, cam, 4)
    small = Camera(R, cam.target_height, fov=fov, pitch=pitch, shift=cam.shift * R / FRAME)
    near, far = pixel_heights(v, mesh.faces, small)
    return {
        "mask": resample_frames(frame_mask[None], R)[0],
        "camera": (small.horizon, float(small.focal)),
        "height": near,
        "far": far,
    }


def make(
    split: str,
    cameras: list[str],
    out: Path,
    seed: int = 0,
    sources: tuple[str, ...] = DEFAULT_SOURCES,
    procedural: int = 36,
    humans: int = 48,
    stretch: float = 0.0,
    quadrupeds: int = 0,
    grounded: int = 0,
) -> None:
    """Write every view of ``split``'s items of ``sources`` under each camera set to ``out`` (npz): ``masks``
    bit-packed (mask > 0.5, (n, R * R / 8)), ``heights`` uint8 over the masks' set pixels in order (nearest
    surface's where a set pixel's centre misses the mesh), ``camera`` (n, 2) at R, ``pitch``. ``quadrupeds``,
    ``grounded``: how many items the ``quadruped`` and ``grounded`` sources draw (80 % of them in train).
    ``stretch`` > 0: each view's shape stretched first (:func:`stretched`, its factors drawn from the seed, the
    item and the view)."""
    views, pitches = [], []
    for k, (item, mesh, topo, (yaw, pitch, fov)) in enumerate(
        split_views(split, cameras, seed, procedural, humans, sources=sources, quadrupeds=quadrupeds, grounded=grounded)
    ):
        if stretch > 0.0:
            mesh = stretched(mesh, np.random.default_rng([seed, stable_hash(item.id), k]), stretch)
        views.append(view_record(mesh, topo, yaw, pitch, fov))
        pitches.append(pitch)
    save(out, views, pitches)


def stretched(mesh: meshes.Mesh, rng: np.random.Generator, stretch: float) -> meshes.Mesh:
    """``mesh`` scaled along x, y and z by factors drawn log-uniformly in [1 / (1 + stretch), 1 + stretch] and
    normalised again: a horse longer or shorter in the leg, a box flatter, a figure stockier; shapes the meshes do
    not hold, each still a solid with true pixel heights (the topology is unchanged)."""
    scale = np.exp(rng.uniform(-np.log1p(stretch), np.log1p(stretch), 3))
    return meshes.normalise(meshes.Mesh(mesh.vertices * scale, mesh.faces))


def save(out: Path, views: list[dict], pitches: list[float]) -> None:
    """Write :func:`view_record` views and their pitches to ``out`` as :func:`make` does."""
    masks, heights, depths = [], [], []

    def steps(rows: np.ndarray) -> np.ndarray:
        return np.clip(np.round(rows * HEIGHT_STEPS / R), 0, 255).astype(np.uint8)

    for view in views:
        solid = view["mask"] > 0.5
        masks.append(np.packbits(solid.ravel()))
        hit = np.isfinite(view["height"])
        near, far = np.nan_to_num(nearest_fill(np.stack([view["height"], view["far"]]), hit))
        heights.append(steps(near[solid]))
        depths.append(steps(np.maximum(near - far, 0.0)[solid]))
    out.parent.mkdir(parents=True, exist_ok=True)
    np.savez_compressed(
        out,
        masks=np.asarray(masks),
        heights=np.concatenate(heights),
        depths=np.concatenate(depths),
        camera=np.asarray([v["camera"] for v in views], np.float32),
        pitch=np.asarray(pitches, np.float32),
    )


def load(paths: list[Path]) -> dict[str, np.ndarray]:
    """The views of several :func:`make` files: ``mask`` (n, R, R) uint8 in {0, 1}, ``height`` (n, R, R) rows of R
    (0 off the mask), ``depth`` (n, R, R) how many rows less the far surface's pixel height is (0 off the mask),
    both float16 (the files' half rows, exactly: tens of thousands of views fit in memory), ``camera`` (n, 2) in
    frames (horizon row / R, focal length / R), ``pitch``."""
    files = [np.load(p) for p in paths]
    for p, f in zip(paths, files, strict=True):
        if "depths" not in f:
            raise ValueError(f"{p} holds no far surfaces (made before they were recorded): make it again")
    n = sum(len(f["camera"]) for f in files)
    out = {
        "mask": np.zeros((n, R, R), np.uint8),
        "height": np.zeros((n, R, R), np.float16),
        "depth": np.zeros((n, R, R), np.float16),
    }
    i = 0
    for f in files:
        m = unpacked_masks(f["masks"])
        part = slice(i, i + len(m))
        out["mask"][part] = m
        for key, name in (("heights", "height"), ("depths", "depth")):
            out[name][part][m] = f[key].astype(np.float32) * R / HEIGHT_STEPS
        i += len(m)
    out["camera"] = np.concatenate([f["camera"] / R for f in files])
    out["pitch"] = np.concatenate([f["pitch"] for f in files])
    return out
