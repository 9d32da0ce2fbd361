"""The camera estimator's data: each view's mask, true camera input and the estimator's input, from the meshes alone.

Each view's camera is drawn exactly as ``training.make_dataset`` draws it (:func:`training.data.generate.view_rng`);
its mask is the dataset's coverage at N = 256 resampled to R. The camera estimator's input is made from the
coverage at N = 256 too, as the engine makes it from a cutout (:data:`ESTIMATOR_KEYS`). ``python -m
training.heights make`` writes a split's views to one npz file (:func:`make`); :func:`load` reads several back.
"""

from __future__ import annotations

from collections.abc import Iterator
from pathlib import Path
from typing import Any

import numpy as np

from ssn_engine.camera import Camera
from ssn_engine.frames import resample_frames
from ssn_engine.methods.camera_estimate import canonical_input, to_canonical

from ..progress import Progress
from . import meshes
from .generate import view_rng
from .meshes import yawed
from .render_bases import mask_coverage, view_camera
from .items import Item
from .sources import DEFAULT_SOURCES, all_items, build_mesh
from .views import VIEWS, draw_view

__all__ = ["ESTIMATOR_KEYS", "KEYS", "KIND_NAMES", "R", "load", "make", "split_views", "unpacked_masks", "view_record"]

FRAME = 256  # the frame the masks are covered at (the engine's N)
R = 128
KIND_NAMES = ("object", "human", "animal")
KEYS = ("mask", "camera", "kind", "pitch")
ESTIMATOR_KEYS = ("estimator", "estimator_camera")  # the camera estimator's 8-bit input from the N = FRAME mask


def view_record(mesh: meshes.Mesh, topo: meshes.Topology, yaw: float, pitch: float, fov: float) -> dict:
    """One view: its mask at R and camera input at R (horizon row, focal length); and the camera estimator's input
    made from the mask at N = FRAME, as the engine makes it, with its target (canonical horizon row and focal length
    over N)."""
    v = np.ascontiguousarray(yawed(mesh.vertices, yaw))
    cam = view_camera(v, FRAME, fov, pitch)
    frame_mask = mask_coverage(v, mesh.faces, topo, cam, 4)
    estimator, framing = canonical_input(frame_mask)
    small = Camera(R, cam.target_height, fov=fov, pitch=pitch, shift=cam.shift * R / FRAME)
    return {
        "mask": resample_frames(frame_mask[None], R)[0],
        "camera": (small.horizon, float(small.focal)),
        "estimator": estimator,
        "estimator_camera": np.array(to_canonical((cam.horizon, float(cam.focal)), framing)) / FRAME,
    }


def split_views(
    split: str,
    cameras: list[str],
    seed: int = 0,
    procedural: int = 36,
    humans: int = 48,
    view_seed: int | None = None,
    sources: tuple[str, ...] = DEFAULT_SOURCES,
    quadrupeds: int = 0,
    grounded: int = 0,
) -> Iterator[tuple[Item, meshes.Mesh, meshes.Topology, tuple[float, float, float]]]:
    """Every view of ``split``'s items of ``sources`` under each camera set, drawn as ``training.make_dataset``
    draws them (``view_seed``, default ``seed``: other views of the same items): (item, mesh, its topology, (yaw,
    pitch, fov)), with a progress line."""
    items = [it for it in all_items(sources, procedural, humans, seed, quadrupeds, grounded) if it.split == split]
    prog = Progress(len(items) * len(cameras))
    for c, which in enumerate(cameras):
        for q, item in enumerate(items):
            mesh = build_mesh(item)
            topo = meshes.topology(mesh)
            for k in range(VIEWS):
                yield (
                    item,
                    mesh,
                    topo,
                    draw_view(k, view_rng(seed if view_seed is None else view_seed, item.id, k), which),
                )
            prog.update(c * len(items) + q + 1, item.id)
    prog.close()


def make(
    split: str,
    cameras: list[str],
    out: Path,
    seed: int = 0,
    procedural: int = 36,
    humans: int = 48,
    view_seed: int | None = None,
) -> None:
    """Write every view of ``split`` under each camera set to ``out`` (npz; masks as float16, the estimator's
    inputs as 8-bit). ``view_seed`` (default: ``seed``, the dataset's own views) draws other views of the same
    items."""
    rec: dict[str, list] = {key: [] for key in KEYS + ESTIMATOR_KEYS}
    for item, mesh, topo, (yaw, pitch, fov) in split_views(split, cameras, seed, procedural, humans, view_seed):
        view = view_record(mesh, topo, yaw, pitch, fov)
        rec["mask"].append(view["mask"].astype(np.float16))
        rec["camera"].append(view["camera"])
        rec["estimator"].append(np.round(view["estimator"] * 255).astype(np.uint8))
        rec["estimator_camera"].append(view["estimator_camera"])
        rec["kind"].append(KIND_NAMES.index(item.kind))
        rec["pitch"].append(pitch)
    out.parent.mkdir(parents=True, exist_ok=True)
    arrays: dict[str, Any] = {k: np.asarray(v) for k, v in rec.items()}
    np.savez_compressed(out, **arrays, cameras=np.array(cameras))


UNKNOWN_KIND = -1  # a view of a surface set, which records no kind


def unpacked_masks(packed: np.ndarray) -> np.ndarray:
    """(n, R, R) bool: the bit-packed masks of a ``training.surface make`` file (``masks``, a row of bytes a
    view)."""
    return np.unpackbits(packed, axis=1)[:, : R * R].reshape(-1, R, R).astype(bool)


def _surface_set(f: Any) -> dict[str, np.ndarray]:
    """A ``training.surface make`` file's views as :data:`KEYS`: its masks (coverage 0 or 1 at R), its cameras at
    R, its pitches, and :data:`UNKNOWN_KIND`. Its many shapes (procedural animals, people in poses, objects with
    parts on the ground) teach the camera estimator too."""
    masks = unpacked_masks(f["masks"]).astype(np.float16)
    return {"mask": masks, "camera": f["camera"], "kind": np.full(len(masks), UNKNOWN_KIND), "pitch": f["pitch"]}


def load(paths: list[Path]) -> dict[str, np.ndarray]:
    """The views of several :func:`make` files or ``training.surface make`` files, concatenated; the camera
    estimator's inputs (:data:`ESTIMATOR_KEYS`) too where every file has them (files made without them lack them)."""
    files = [np.load(p) for p in paths]
    estimator = all(set(ESTIMATOR_KEYS) <= set(f.files) for f in files)
    keys = KEYS + (ESTIMATOR_KEYS if estimator else ())
    parts = [_surface_set(f) if "masks" in f.files else {k: f[k] for k in keys} for f in files]
    return {k: np.concatenate([p[k] for p in parts]) for k in keys}
