"""Check the canvas truths against Mitsuba 3 (Embree ray casting, ``llvm_ad_rgb``), as
:mod:`training.benchmark_bases` does for the training bases.

Two checks per case, on every ``stride``-th canvas pixel that sees the ground:

- *same directions*: Mitsuba casts the truth's own disk directions; the shadows must agree up to the
  truth's 16-bit storage (this checks the scan-conversion kernel, the camera and the weighting);
- *independent*: Mitsuba casts ``samples`` directions drawn uniformly at random over the disk's cap by a
  different parametrisation (cos alpha uniform, azimuth uniform); the difference then is the truth's
  sampling error plus Mitsuba's Monte Carlo noise (its standard deviation is reported beside it).
"""

from __future__ import annotations

import math
from pathlib import Path
from typing import Any

import numpy as np

from ssn_engine.hemisphere import direction

from . import cases
from .render_set import group_scene, truth_directions


def random_cap(elevation: float, azimuth: float, angle: float, count: int, rng: np.random.Generator) -> np.ndarray:
    """``count`` directions uniform in solid angle over a disk's cap, camera basis (independent of
    :func:`training.canvas_eval.disk.disk_directions`: a random frame about the centre, no strata)."""
    centre = direction(np.radians(elevation), np.radians(azimuth))
    helper = np.array([1.0, 0.0, 0.0]) if abs(centre[0]) < 0.9 else np.array([0.0, 0.0, 1.0])
    t1 = np.cross(centre, helper)
    t1 /= np.linalg.norm(t1)
    t2 = np.cross(centre, t1)
    cos_a = 1.0 - rng.random(count) * (1.0 - math.cos(math.radians(angle) / 2))
    sin_a = np.sqrt(1.0 - cos_a**2)
    phi = 2 * np.pi * rng.random(count)
    return cos_a[:, None] * centre + sin_a[:, None] * (np.cos(phi)[:, None] * t1 + np.sin(phi)[:, None] * t2)


def mitsuba_shadow(vertices: np.ndarray, faces: np.ndarray, points: np.ndarray, dirs: np.ndarray) -> np.ndarray:
    """s at ground ``points`` (P, 3) for world directions ``dirs`` (S, 3), each weighted by its cosine to the
    zenith, by Mitsuba 3's ``ray_test``. (P,) float64."""
    import drjit as dr
    import mitsuba

    mi: Any = mitsuba  # its variant's classes appear only once a variant is set
    mi.set_variant("llvm_ad_rgb")
    m = mi.Mesh("m", vertex_count=len(vertices), face_count=len(faces))
    params = mi.traverse(m)
    params["vertex_positions"] = dr.ravel(mi.TensorXf(vertices.astype(np.float32)))
    params["faces"] = dr.ravel(mi.TensorXu(faces.astype(np.uint32)))
    params.update()
    scene = mi.load_dict({"type": "scene", "m": m})
    blocked = np.zeros(len(points))
    chunk = max(1, 2_000_000 // len(points))
    for start in range(0, len(dirs), chunk):
        d = dirs[start : start + chunk]
        o = np.repeat(points[None], len(d), 0).reshape(-1, 3).astype(np.float32)
        w = np.repeat(d[:, None], len(points), 1).reshape(-1, 3).astype(np.float32)
        ray = mi.Ray3f(mi.Point3f(o[:, 0], o[:, 1], o[:, 2]), mi.Vector3f(w[:, 0], w[:, 1], w[:, 2]))
        hit = np.asarray(scene.ray_test(ray)).reshape(len(d), len(points))
        blocked += d[:, 1] @ hit
    return blocked / dirs[:, 1].sum()


def compare(data: Path, groups: int = 3, samples: int = 1024, stride: int = 4, log=print) -> list[dict]:
    """Both checks for ``groups`` groups spread over the test set, every size; prints a line per case and
    returns the figures (max and mean |difference|, Mitsuba's noise)."""
    all_groups = cases.read_groups(data)
    picked = [all_groups[i] for i in np.linspace(0, len(all_groups) - 1, groups).round().astype(int)]
    rows = []
    for group in picked:
        vertices, mesh, _, canvas = group_scene(group)
        g, down = canvas.camera.ground_points()
        g, down = g[: group.height : stride, ::stride], down[: group.height : stride, ::stride]
        points = g[down]
        for angle in cases.ANGLES:
            truth = cases.read_truth(data, group, angle)[::stride, ::stride][down]
            same = mitsuba_shadow(vertices, mesh.faces, points, canvas.camera.to_world(truth_directions(group, angle)))
            rng = np.random.default_rng([group.seed, 7, int(round(100 * angle))])
            dirs = canvas.camera.to_world(random_cap(group.elevation, group.azimuth, angle, samples, rng))
            independent = mitsuba_shadow(vertices, mesh.faces, points, dirs)
            noise = np.sqrt(np.clip(independent * (1 - independent), 0.0, None) / samples)
            row = {
                "group": group.name,
                "angle": angle,
                "pixels": int(len(points)),
                "same_max": float(np.abs(same - truth).max()),
                "same_mean": float(np.abs(same - truth).mean()),
                "independent_max": float(np.abs(independent - truth).max()),
                "independent_mean": float(np.abs(independent - truth).mean()),
                "independent_mean_shadowed": float(np.abs(independent - truth)[truth > 0.01].mean()),
                "noise_mean_shadowed": float(noise[truth > 0.01].mean()),
            }
            rows.append(row)
            log(
                f"{group.name:28s} {angle:5g} deg  {row['pixels']:6d} px  same directions: max {row['same_max']:.4f} "
                f"mean {row['same_mean']:.6f}  independent: mean {row['independent_mean']:.4f} "
                f"(shadowed px {row['independent_mean_shadowed']:.4f}, Mitsuba noise {row['noise_mean_shadowed']:.4f})"
                f" max {row['independent_max']:.3f}"
            )
    return rows


__all__ = ["compare", "mitsuba_shadow", "random_cap"]
