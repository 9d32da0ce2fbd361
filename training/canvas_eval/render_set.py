"""Render the canvas-scale test set (:mod:`.cases`) to a folder, resuming where a previous run stopped."""

from __future__ import annotations

import time
from dataclasses import asdict, replace
from pathlib import Path

import numpy as np

from ssn_engine.hard_light import lowest_pixel
from ssn_engine.hemisphere import direction
from training.data import meshes, sources
from training.data.items import stable_hash
from training.data.raycast import ray_distances

from . import cases, disk, out_of_source, render


def planned_groups(
    width: int, height: int, shapes: int | None, lights: int, seed: int, split: str = "test", floating: bool = False
) -> list[cases.Group]:
    """The set's groups: the picked held-out shapes of ``split`` (the first ``shapes`` of them, None: all; every
    shape of the out-of-source split);
    ``floating``: each lifted off the ground (:func:`cases.make_groups`)."""
    every = split == out_of_source.SPLIT  # a whole source held out: every shape of it
    items = cases.pick_shapes(sources.manifest_items(), quota=None if every else cases.KIND_QUOTA, split=split)
    if not items:
        raise ValueError(
            f"the meshes' manifest ({meshes.SHARED_MESHES}) has no shapes of the split {split!r}"
            + (" (prepare-outsource writes them; point SSN_MESHES at its folder)" if every else "")
        )
    return [_shadow_on_canvas(g) for g in cases.make_groups(items[:shapes], lights, width, height, seed, floating)]


def _shadow_on_canvas(group: cases.Group, attempts: int = 50) -> cases.Group:
    """A floating ``group``, under its next light direction (:func:`cases.relit`) while its light casts less than
    ``cases.SHADOW_ON_CANVAS`` of it onto the canvas (a low light from the front throws a lifted shape's shadow
    below the canvas: a case no prediction can score); a resting group as it is (its shadow starts at it)."""
    if group.lift_share <= 0:
        return group
    vertices, _, _, canvas = group_scene(group)
    for attempt in range(attempts):
        lit = cases.relit(group, attempt) if attempt else group
        if shadow_share(vertices, canvas, lit.elevation, lit.azimuth) >= cases.SHADOW_ON_CANVAS:
            return lit
    raise ValueError(f"{group.name}: no light of {attempts} drawn casts its shadow onto the canvas")


def shadow_share(vertices: np.ndarray, canvas: render.CanvasCamera, elevation: float, azimuth: float) -> float:
    """The share of ``vertices`` whose shadow, cast along the light at ``elevation`` and ``azimuth`` (degrees, the
    conventions' camera-relative directions) onto the ground, lands on ``canvas``."""
    cam = canvas.camera
    d = cam.to_world(direction(np.radians(elevation), np.radians(azimuth)))  # the disk's centre, towards the light
    ground = vertices - vertices[:, 1:2] / d[1] * d
    col, row = cam.project(ground).T
    ahead = (ground - cam.centre) @ cam.view > 0
    return float(np.mean(ahead & (col >= 0) & (col < canvas.width) & (row >= 0) & (row < canvas.height)))


def _same_plan(a: cases.Group, b: cases.Group) -> bool:
    skip = {"horizon", "fov", "lift"}
    return {k: v for k, v in asdict(a).items() if k not in skip} == {
        k: v for k, v in asdict(b).items() if k not in skip
    }


def group_scene(group: cases.Group) -> tuple[np.ndarray, meshes.Mesh, meshes.Topology, render.CanvasCamera]:
    """A group's yawed vertices, its mesh and topology, and its canvas camera."""
    item = next((it for it in sources.manifest_items() if it.id == group.shape), None)
    if item is None:
        raise ValueError(f"{group.name}: shape {group.shape!r} is not in the meshes' manifest")
    mesh = sources.build_mesh(item)
    vertices = np.ascontiguousarray(meshes.yawed(mesh.vertices, group.yaw))
    vertices[:, 1] += group.lift_share * float(np.ptp(vertices[:, 1]))  # a floating case: off the ground
    return vertices, mesh, meshes.topology(mesh), render.canvas_camera(vertices, group.width, group.height, group.pitch)


def true_lift(vertices: np.ndarray, faces: np.ndarray, canvas: render.CanvasCamera, alpha: np.ndarray) -> float:
    """The lift in canvas rows (conventions, "Lift and thickness") of a floating shape whose cutout's coverage
    is ``alpha``: the rows from the cutout's :func:`lowest_pixel` (its centre) down to the image of the ground
    point beneath the surface point seen through it."""
    row, col = lowest_pixel(alpha)
    cam = canvas.camera
    # the centre first; where the faces just miss it (the pixel half covered), the nearest covered point in it
    points = (np.arange(render.MASK_SAMPLES) + 0.5) / render.MASK_SAMPLES - 0.5
    offsets = sorted(((dy, dx) for dy in points for dx in points), key=lambda o: o[0] ** 2 + o[1] ** 2)
    for dy, dx in [(0.0, 0.0), *offsets]:
        ray = cam.rays(col + 0.5 + dx, row + 0.5 + dy)
        t = float(ray_distances(cam.centre[None], ray[None], vertices, faces)[0])
        if np.isfinite(t):
            point = cam.centre + t * ray
            foot = cam.project_xyz(point[:1], np.zeros(1), point[2:])[1]
            return float(foot[0] - (row + 0.5))
    raise ValueError(f"no face of the mesh is seen through the cutout's lowest pixel ({row}, {col})")


def truth_directions(group: cases.Group, angle: float) -> np.ndarray:
    """The disk's directions a group's truth at size ``angle`` is rendered with (camera basis)."""
    rng = np.random.default_rng([group.seed, stable_hash(group.name), int(round(100 * angle))])
    return disk.disk_directions(group.elevation, group.azimuth, angle, disk.samples_for(angle), rng)


def render_group(root: Path, group: cases.Group, log=print) -> cases.Group:
    """Render one group's cutout and every missing truth (at each of ``group.angles``); returns the group with
    its canvas camera (and, floating, its lift)."""
    vertices, mesh, topo, canvas = group_scene(group)
    if not cases.cutout_path(root, group).is_file():
        cases.write_cutout(root, group, render.canvas_mask(vertices, mesh.faces, topo, canvas))
    lift = 0.0
    if group.lift_share > 0:  # counted on the cutout as the CLI reads it
        lift = round(true_lift(vertices, mesh.faces, canvas, cases.read_mask(root, group)), 2)
    group = replace(group, horizon=canvas.horizon, fov=canvas.fov, lift=lift)
    for angle in group.angles:
        if cases.truth_path(root, group, angle).is_file():
            continue
        t0 = time.perf_counter()
        dirs = canvas.camera.to_world(truth_directions(group, angle))
        s = render.disk_shadow(vertices, mesh.faces, topo, canvas, dirs)
        cases.write_truth(root, group, angle, s)
        log(f"  {group.name} {angle:g} deg: {len(dirs)} directions, {time.perf_counter() - t0:.1f} s")
    return group


def render_set(
    root: Path,
    width: int = 1024,
    height: int = 768,
    shapes: int | None = None,
    lights: int = 2,
    seed: int = 0,
    log=print,
    split: str = "test",
    floating: bool = False,
) -> list[cases.Group]:
    """Render (or finish rendering) the set of ``split``'s shapes under ``root`` (the test set; "val": the same
    of the validation shapes, to choose models by without looking at the test set); returns its groups.

    Raises
    ------
    ValueError
        ``root`` holds a test set planned with other settings.
    """
    root = Path(root)
    plan = planned_groups(width, height, shapes, lights, seed, split, floating)
    if (root / "cases.json").is_file():
        done = cases.read_groups(root)
        if len(done) != len(plan) or not all(_same_plan(a, b) for a, b in zip(done, plan, strict=True)):
            raise ValueError(f"{root} holds a test set rendered with other settings; choose another folder")
    groups = list(plan)
    t_start = time.perf_counter()
    for i, group in enumerate(plan):
        log(
            f"[{i + 1}/{len(plan)}] {group.name} ({group.kind}, pitch {group.pitch:g}, light {group.elevation:g} / "
            f"{group.azimuth:g} deg)"
        )
        groups[i] = render_group(root, group, log)
        cases.write_groups(root, groups[: i + 1] + plan[i + 1 :])
    log(f"done: {len(plan)} groups in {time.perf_counter() - t_start:.0f} s")
    return groups


__all__ = [
    "group_scene",
    "planned_groups",
    "render_group",
    "render_set",
    "shadow_share",
    "true_lift",
    "truth_directions",
]
