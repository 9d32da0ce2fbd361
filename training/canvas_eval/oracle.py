"""What the traced representation can do given the true geometry: ``python -m training.canvas_eval oracle``.

The tracer (:mod:`ssn_engine.hard_light`) casts each pixel of the cutout as a segment along its camera ray,
from the surface the pixel shows to that surface plus the object's depth there, onto the ground along the
light. It guesses both ends from the outline alone (cards on the contact line, :func:`depth_map`'s round
cross-section). Here the segments come from the test shape's mesh instead, one end or both, so that the
score says how much of the error is in each guess:

- ``true surface and depth``: from the first surface a pixel's ray meets to the last (the shape's true solid,
  gaps behind it filled);
- ``true surface, round depth``: from the true first surface, as deep as :func:`depth_map` says;
- ``true surface only``: the visible surface alone (a per-pixel height map, as SSG and PixHt-Lab trace);
- ``smooth surface, round depth``: the true surface's distance blurred by a Gaussian of ``SMOOTH`` of the
  object's height (what a model reading a coarse depth from the outline could give), as deep as
  :func:`depth_map` says;
- ``column's surface, round depth``: one distance a column (the median of the true surface's), as a card a
  column standing at the truth's own place would be (the best the contact line's cards can do), as deep.

And the product's own tracer (the shipped model, the true camera, the cutout as one object; a floating group's
with its true lift, the true pixel heights then those of its shape standing, :func:`standing_shape`), each
pixel's surface placed by pixel heights (how far below a pixel the image of the ground under its surface lies),
traced as the product traces a 0.53-degree sun (:class:`ssn_engine.hard_light.ContactTracer`):

- ``traced, model's heights``: the traced part alone, at the surface model's reading (what ships);
- ``traced, true heights``: the traced part alone, at the mesh's visible surface's pixel heights;
- ``product, true heights``: the whole shadow (the traced part with the network's, as the CLI gives it) at
  the true pixel heights: what a perfect surface model reading the visible surface would give;
- ``traced, true heights and depths`` and ``product, true heights and depths``: the same, each pixel's segment
  ending at the pixel height of its far surface (the last face its ray meets), as a perfect surface model
  reading the object's depth as well would place it.

Each splatted variant is a hard shadow (no penumbra: compare it with the 0.53-degree truths), splatted from
``SUPERSAMPLE`` x ``SUPERSAMPLE`` rays a pixel and ``SAMPLES`` points along each, the holes between splats
closed over a pixel or two, scored as ``score`` scores the CLI (ZNCC on the visible ground; the fine
metrics, band-pass ZNCC and gradient energy, beside it).
"""

from __future__ import annotations

import json
import math
import typing
from pathlib import Path

import numba
import numpy as np
from scipy import ndimage

from ssn_engine.camera import FORWARD, RIGHT, Camera
from ssn_engine.frames import nearest_fill
from ssn_engine.framing import CanvasShadow
from ssn_engine.hard_light import depth_map, light_direction
from ssn_engine.host_kit.light_map import LightMap
from ssn_engine.imageio import load_image
from ssn_engine.methods import ShadowMethod, load_method
from ssn_engine.session import ShadowSession

from . import cases, metrics, render_set
from .sheet import default_groups, panel_sheet

SUPERSAMPLE = 3  # rays per pixel side
SAMPLES = 32  # points cast along each ray's segment
SMOOTH = 0.1  # the smoothed surface's Gaussian, as a share of the object's height
VARIANTS = (
    "true surface and depth",
    "true surface, round depth",
    "true surface only",
    "smooth surface, round depth",
    "column's surface, round depth",
)
TRACED = (  # the product's tracer
    "traced, model's heights",
    "traced, true heights",
    "product, true heights",
    "traced, true heights and depths",
    "product, true heights and depths",
)
FINE_METRICS = ("bandpass_zncc", "gradient_energy")  # scored beside ZNCC: "<variant>, <metric>"


@numba.njit(cache=True)
def _raster(cols, rows, depth, faces, front, back):  # pragma: no cover - compiled
    """The nearest and farthest camera depth of ``faces`` at each pixel centre of ``front`` / ``back``."""
    h, w = front.shape
    for f in range(faces.shape[0]):
        a, b, c = faces[f, 0], faces[f, 1], faces[f, 2]
        x0, y0, z0 = cols[a], rows[a], depth[a]
        x1, y1, z1 = cols[b], rows[b], depth[b]
        x2, y2, z2 = cols[c], rows[c], depth[c]
        if z0 <= 0 or z1 <= 0 or z2 <= 0:
            continue
        den = (y1 - y2) * (x0 - x2) + (x2 - x1) * (y0 - y2)
        if abs(den) < 1e-12:
            continue
        c0, c1 = max(0, int(math.floor(min(x0, x1, x2) - 0.5))), min(w - 1, int(math.ceil(max(x0, x1, x2))))
        r0, r1 = max(0, int(math.floor(min(y0, y1, y2) - 0.5))), min(h - 1, int(math.ceil(max(y0, y1, y2))))
        for r in range(r0, r1 + 1):
            py = r + 0.5
            for q in range(c0, c1 + 1):
                px = q + 0.5
                l0 = ((y1 - y2) * (px - x2) + (x2 - x1) * (py - y2)) / den
                l1 = ((y2 - y0) * (px - x2) + (x0 - x2) * (py - y2)) / den
                l2 = 1.0 - l0 - l1
                if l0 < 0 or l1 < 0 or l2 < 0:
                    continue
                z = 1.0 / (l0 / z0 + l1 / z1 + l2 / z2)  # perspective-correct: 1 / depth is linear on screen
                front[r, q] = min(front[r, q], z)
                back[r, q] = max(back[r, q], z)


@numba.njit(cache=True)
def _splat(rays, t0, t1, samples, centre, w, project, out):  # pragma: no cover - compiled
    """Mark ``out``'s pixels hit by the ground shadows (along ``w``) of ``samples`` points on each ray's segment
    centre + t rays[i], t from t0[i] to t1[i]; ``project`` (3, 4) maps a world point to homogeneous pixels."""
    h, wd = out.shape
    for i in range(rays.shape[0]):
        for k in range(samples):
            t = t0[i] + (t1[i] - t0[i]) * (k + 0.5) / samples
            p = centre + t * rays[i]
            lift = max(p[1], 0.0) / w[1]
            g0, g2 = p[0] - lift * w[0], p[2] - lift * w[2]
            x = project[0, 0] * g0 + project[0, 2] * g2 + project[0, 3]
            y = project[1, 0] * g0 + project[1, 2] * g2 + project[1, 3]
            z = project[2, 0] * g0 + project[2, 2] * g2 + project[2, 3]
            if z <= 1e-9:
                continue
            col, row = int(x / z), int(y / z)
            if 0 <= row < h and 0 <= col < wd:
                out[row, col] = 1.0


def surface_depths(vertices: np.ndarray, faces: np.ndarray, cam: Camera, width: int, height: int, ss: int):
    """The nearest and farthest camera depth of the mesh at each of ``ss`` x ``ss`` points a canvas pixel
    ((height ss, width ss), inf / -inf where no face is)."""
    rel = vertices - cam.centre
    depth = rel @ cam.view
    col, row = cam.project_xyz(vertices[:, 0], vertices[:, 1], vertices[:, 2])
    front = np.full((height * ss, width * ss), np.inf)
    back = np.full((height * ss, width * ss), -np.inf)
    _raster(col * ss, row * ss, depth, np.ascontiguousarray(faces, np.int64), front, back)
    return front, back


def foot_image_rows(cam: Camera, rays: np.ndarray, depth: np.ndarray) -> np.ndarray:
    """The image rows on ``cam`` of the feet (the ground points straight below) of the points at camera depth
    ``depth`` (n,) along ``rays`` (n, 3)."""
    points = cam.centre + depth[:, None] * rays
    return cam.project_xyz(points[:, 0], np.zeros(len(points)), points[:, 2])[1]


def cast(
    cam: Camera,
    cols: np.ndarray,
    rows: np.ndarray,
    t0: np.ndarray,
    t1: np.ndarray,
    w: np.ndarray,
    size: tuple[int, int],
) -> np.ndarray:
    """The hard shadow (height, width) = ``size`` of the segments from camera depth ``t0`` to ``t1`` along the
    rays through canvas points (``cols``, ``rows``), under a light along ``w`` (world, (3,))."""
    out = np.zeros(size, np.float32)
    rays = np.ascontiguousarray(cam.rays(cols, rows))
    _splat(
        rays,
        np.ascontiguousarray(t0, np.float64),
        np.ascontiguousarray(t1, np.float64),
        SAMPLES,
        cam.centre,
        np.asarray(w, np.float64),
        cam.projection(),
        out,
    )
    return ndimage.binary_closing(out > 0, np.ones((3, 3), bool), iterations=2).astype(np.float32)


def hard_shadows(group: cases.Group, alpha: np.ndarray, w: np.ndarray, ss: int = SUPERSAMPLE) -> dict[str, np.ndarray]:
    """Each variant's hard shadow (H, W) of ``group``'s shape under a light along ``w`` (world, (3,)),
    ``alpha`` its cutout."""
    vertices, mesh, _, canvas = render_set.group_scene(group)
    cam = canvas.camera
    front, back = surface_depths(vertices, mesh.faces, cam, group.width, group.height, ss)
    yy, xx = np.nonzero(np.isfinite(front))
    cols, rows = (xx + 0.5) / ss, (yy + 0.5) / ss
    t_front, t_back = front[yy, xx], back[yy, xx]
    rays = cam.rays(cols, rows)
    run = np.hypot(rays @ RIGHT, rays @ FORWARD)  # horizontal distance a unit of camera depth goes
    pixels = depth_map(alpha)[np.minimum(yy // ss, group.height - 1), np.minimum(xx // ss, group.width - 1)]

    def round_end(t: np.ndarray) -> np.ndarray:  # the round depth's canvas pixels, as world units at depth t
        return t + pixels * (t / float(cam.focal)) / run

    # the surface's horizontal distance from the camera on the grid, smoothed, and one a column
    distance = np.full(front.shape, np.nan)
    distance[yy, xx] = t_front * run
    height = float(np.ptp(yy))
    hit = np.isfinite(distance).astype(np.float64)
    k = max(1, int(SMOOTH * height / 4))  # blurred on a copy k times smaller: the Gaussian spans 4 of its pixels

    def reduced(a: np.ndarray) -> np.ndarray:
        rh, rw = a.shape
        return np.pad(a, ((0, -rh % k), (0, -rw % k))).reshape(-(-rh // k), k, -(-rw // k), k).mean(axis=(1, 3))

    sigma = SMOOTH * height / k
    smooth = ndimage.gaussian_filter(reduced(np.nan_to_num(distance)), sigma)
    smooth = smooth / np.maximum(ndimage.gaussian_filter(reduced(hit), sigma), 1e-9)
    column = np.nanmedian(np.where(hit > 0, distance, np.nan)[:, np.unique(xx)], axis=0)
    t_smooth = smooth[yy // k, xx // k] / run
    t_column = column[np.searchsorted(np.unique(xx), xx)] / run
    segments = {
        VARIANTS[0]: (t_front, t_back),
        VARIANTS[1]: (t_front, round_end(t_front)),
        VARIANTS[2]: (t_front, t_front),
        VARIANTS[3]: (t_smooth, round_end(t_smooth)),
        VARIANTS[4]: (t_column, round_end(t_column)),
    }
    size = (group.height, group.width)
    return {name: cast(cam, cols, rows, t0, t1, w, size) for name, (t0, t1) in segments.items()}


def true_heights(
    vertices: np.ndarray, faces: np.ndarray, cam: Camera, size: tuple[int, int], session: ShadowSession
) -> np.ndarray:
    """The pixel heights (2, N, N) on ``session``'s frame of the mesh seen by ``cam`` on a canvas of ``size``
    (height, width): at each frame pixel its visible surface's foot (the image of the ground straight below
    it) less its own row, and its far surface's (the last face its ray meets), frame rows (off the mesh,
    standing on its nearest covered pixel's feet)."""
    height, width = size
    surfaces = surface_depths(vertices, faces, cam, width, height, 1)
    n, framing = session.mask.shape[0], session.framing
    fy, fx = np.mgrid[0:n, 0:n] + 0.5
    cx, cy = (fx - framing.offset_x) / framing.scale, (fy - framing.offset_y) / framing.scale  # canvas points
    at = np.clip(cy.astype(int), 0, height - 1), np.clip(cx.astype(int), 0, width - 1)
    hit = np.isfinite(surfaces[0][at]) & (cx >= 0) & (cy >= 0) & (cx < width) & (cy < height)
    rays = cam.rays(cx[hit], cy[hit])
    feet = np.zeros((2, n, n), np.float32)
    for k, depth in enumerate(surfaces):
        feet[k][hit] = foot_image_rows(cam, rays, depth[at][hit]) * framing.scale + framing.offset_y  # frame rows
    return nearest_fill(feet, hit) - fy


def traced_shadows(
    data: Path, group: cases.Group, method: ShadowMethod, light: LightMap, angle: float
) -> dict[str, np.ndarray]:
    """The product tracer's shadows (H, W) of ``group``'s cutout under ``light`` (one disk of ``angle``
    degrees), with the true camera (and a floating group's true lift): :data:`TRACED`."""
    cutout = load_image(str(cases.cutout_path(data, group)))[0][..., 3]
    session = ShadowSession(cutout, method, group.horizon, group.fov)
    session.set_geometry(group.lift)
    u, v = light.lights[0].u, light.lights[0].v
    vertices, mesh, _, canvas = render_set.group_scene(group)
    heights = true_heights(
        standing_shape(vertices, canvas.camera), mesh.faces, canvas.camera, (group.height, group.width), session
    )
    shown = {TRACED[0]: CanvasShadow(*session.tracer.shadow(u, v, angle, session.framing))}
    for given, (traced, product) in ((heights[:1], TRACED[1:3]), (heights, TRACED[3:5])):
        method_given = typing.cast(ShadowMethod, GivenHeights(method, given))
        standing = ShadowSession(cutout, method_given, group.horizon, group.fov)  # on the true surface
        standing.set_geometry(group.lift)
        shown[traced] = CanvasShadow(*standing.tracer.shadow(u, v, angle, standing.framing))
        shown[product] = standing.render(light)
    return {k: on_canvas(v, (group.height, group.width)) for k, v in shown.items()}


def standing_shape(vertices: np.ndarray, cam: Camera) -> np.ndarray:
    """``vertices`` of a shape as the engine reads it from its image: standing on the ground. A floating shape
    (its lowest point above the ground) shows the same image as itself scaled about the camera's centre until it
    stands (conventions, "Lift and thickness"), whose pixel heights a surface model reads; the engine lifts that
    by the artist's lift. A standing shape is returned as it is."""
    c = np.asarray(cam.centre, np.float64)
    low = float(vertices[:, 1].min())
    if low <= 1e-9:
        return vertices
    return c + (vertices - c) * (c[1] / (c[1] - low))


class GivenHeights:
    """``method``, reading ``heights`` (C, N, N) as every mask's pixel heights (of the visible surface, and of
    the far surface where C = 2)."""

    def __init__(self, method: ShadowMethod, heights: np.ndarray) -> None:
        self._method, self._heights = method, heights

    def __getattr__(self, name: str) -> object:
        return getattr(self._method, name)

    def pixel_heights(self, masks: np.ndarray, cameras: np.ndarray | None) -> np.ndarray:
        return np.repeat(self._heights[None], len(masks), 0)


def on_canvas(shadow: CanvasShadow, size: tuple[int, int]) -> np.ndarray:
    """``shadow`` (clipped to the canvas) on a zero canvas of ``size`` (height, width), in 8 bits as the CLI
    writes it."""
    return np.round(np.clip(shadow.full_canvas(size[1], size[0]), 0.0, 1.0) * 255) / 255


SHORT = {  # the sheet's captions
    VARIANTS[0]: "true solid",
    VARIANTS[1]: "true surface, round",
    VARIANTS[2]: "true surface only",
    VARIANTS[3]: "smooth surface, round",
    VARIANTS[4]: "column's surface, round",
    TRACED[0]: "traced, model",
    TRACED[1]: "traced, true heights",
    TRACED[2]: "product, true heights",
    TRACED[3]: "traced, true depths",
    TRACED[4]: "product, true depths",
}


def run_oracle(
    data: Path,
    out: Path | None = None,
    names: list[str] | None = None,
    sheet: Path | None = None,
    log=print,
) -> dict:
    """Score every variant on each group of the test set at ``data`` against its 0.53-degree truth; prints a
    line a group and the means, and writes them to ``out`` (json) when given; ``sheet``: a picture of the truth
    and every variant for four groups spread over the set (:func:`sheet.default_groups`)."""
    groups = [g for g in cases.read_groups(data) if not names or g.name in names]
    method = load_method("ssn").method
    pictured = set(default_groups(groups, min(4, len(groups)))) if sheet is not None else set()
    panels = []
    rows = []
    for g in groups:
        alpha = cases.read_mask(data, g).astype(np.float32)
        truth = cases.read_truth(data, g, cases.ANGLES[0])
        light = LightMap.from_json(cases.light_path(data, g, cases.ANGLES[0]).read_text())
        shadows = hard_shadows(g, alpha, light_direction(light.lights[0].u, light.lights[0].v))
        shadows.update(traced_shadows(data, g, method, light, cases.ANGLES[0]))
        scores = {k: metrics.score_case(v, truth, alpha, g.horizon) for k, v in shadows.items()}
        row = {"group": g.name, **{k: scores[k]["zncc"] for k in shadows}}
        row.update({f"{k}, {m}": scores[k][m] for k in shadows for m in FINE_METRICS})
        log(g.name + "  " + "  ".join(f"{k}: {row[k]:.3f}" for k in shadows))
        if g.name in pictured:
            shown = [(f"{g.name}: truth", truth)] + [(f"{SHORT[k]} {row[k]:.2f}", v) for k, v in shadows.items()]
            panels.append([(caption, s, alpha) for caption, s in shown])
        rows.append(row)
    means = {k: float(np.mean([r[k] for r in rows])) for k in rows[0] if k != "group"} if rows else {}
    log("mean  " + "  ".join(f"{k}: {v:.3f}" for k, v in means.items()))
    result = {"angle": cases.ANGLES[0], "groups": rows, "means": means}
    if sheet is not None:
        panel_sheet(panels, sheet)
    if out is not None:
        Path(out).parent.mkdir(parents=True, exist_ok=True)
        Path(out).write_text(json.dumps(result, indent=1))
    return result


__all__ = [
    "TRACED",
    "VARIANTS",
    "GivenHeights",
    "cast",
    "foot_image_rows",
    "hard_shadows",
    "on_canvas",
    "run_oracle",
    "standing_shape",
    "surface_depths",
    "traced_shadows",
    "true_heights",
]
