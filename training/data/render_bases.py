"""Occlusion bases, AO and masks of one view by contour-edge scan conversion (numba).

The ground point g seen through a pixel is occluded from direction w (w_y > 0)
exactly when g lies inside the object's parallel projection onto the ground
along w (the object is above y = 0, so the line through g along w can only
meet it at t > 0). That projection is the union of the projected triangles.

Each projected triangle f covers g with winding number +-1, its sign being
sign(n_f . w) up to one global sign, so sum_f sign(n_f . w) * winding_f(g)
counts the triangles covering g (again up to one global sign), and g is in
shadow iff the count is non-zero. Windings are sums of edge crossings, so the
count is a sum over undirected edges e of a coefficient
c_e(w) = sum over faces f at e of sign(n_f . w) * (+1 or -1 for the face's
direction along e). Edges between two faces facing the same way cancel; only
contour and boundary edges remain, which is what makes this fast.

Each image row below the horizon sees a ground line z = const, with x affine
in the column (the camera's right vector is horizontal), so a ground edge
crossing a row contributes +-c_e to every pixel centre right of its crossing:
a difference array per row, then a running sum. Pixel centres are point
sampled exactly (no approximation beyond float rounding); rows above the
horizon get no shadow.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numba
import numpy as np
from numba import njit, prange

from ssn_engine.camera import Camera
from ssn_engine.hemisphere import stratified_directions, texel_weights

from .meshes import Mesh, Topology, face_normals, topology, yawed

MIXED = 2  # face code: n_f . w changes sign over the texel's directions


@dataclass
class GroundRows:
    """The ground lines seen by the frame rows: rows >= first reach the ground.

    Pixel (i, j)'s ground point is (x0[i] + j * dx[i], 0, z[i]); z increases with i.
    ``rowmap`` maps a ground depth to its continuous frame row (see ``_first_row``).
    """

    first: int
    z: np.ndarray
    x0: np.ndarray
    dx: np.ndarray
    rowmap: np.ndarray


def ground_rows(camera: Camera) -> GroundRows:
    """Per-row ground lines of a camera, from :meth:`Camera.ground_points`."""
    n = camera.n
    points, down = camera.ground_points()
    rows = np.flatnonzero(down[:, 0])
    first = int(rows[0]) if rows.size else n
    if not np.array_equal(down, np.broadcast_to(down[:, :1], down.shape)) or (
        rows.size and not np.array_equal(rows, np.arange(first, n))
    ):
        raise ValueError("unexpected horizon layout")
    z = np.full(n, np.inf)
    x0 = np.zeros(n)
    dx = np.ones(n)
    z[first:] = points[first:, 0, 2]
    x0[first:] = points[first:, 0, 0]
    dx[first:] = (points[first:, -1, 0] - points[first:, 0, 0]) / max(n - 1, 1)
    if np.any(np.diff(z[first:]) <= 0) or np.any(dx[first:] <= 0):
        raise ValueError("ground rows are not ordered front to back")
    cy, cz = camera.centre[1], camera.centre[2]
    up, view = camera.up, camera.view
    rowmap = np.array(
        [
            0.5 * n + camera.shift,
            camera.focal,
            -cy * up[1] - cz * up[2],
            up[2],
            -cy * view[1] - cz * view[2],
            view[2],
        ]
    )
    return GroundRows(first, z, x0, dx, rowmap)


@njit(cache=True, inline="always")
def _first_row(z, rowmap, row_z, first):
    """First row i >= first with row_z[i] >= z (len(row_z) if none).

    ``rowmap`` = (r0, f, a, b, c, d) gives the continuous row of ground depth z,
    r0 - f (a + b z) / (c + d z), valid where c + d z > 0 (in front of the
    camera); the guess is then corrected against ``row_z`` so the answer is exact.
    """
    nrows = row_z.shape[0]
    den = rowmap[4] + rowmap[5] * z
    if den <= 0.0:
        i = nrows
    else:
        x = rowmap[0] - rowmap[1] * (rowmap[2] + rowmap[3] * z) / den - 0.5
        if x <= first:
            i = first
        elif x >= nrows:
            i = nrows
        else:
            i = int(math.ceil(x))
    while i > first and row_z[i - 1] >= z:
        i -= 1
    while i < nrows and row_z[i] < z:
        i += 1
    return i


@njit(cache=True, inline="always")
def _scan_edge(px, pz, qx, qz, coef, row_z, row_x0, row_dx, rowmap, first, diff, box):
    """Add the crossings of edge P->Q (coefficient ``coef``) with the rows' lines to ``diff``.

    Rows with zlo <= z < zhi are crossed (half-open, so shared vertices count
    once). ``box`` = [row min, row max, column min] of the touched entries.
    """
    if pz == qz:
        return
    if pz < qz:
        zlo, zhi, sgn = pz, qz, coef
    else:
        zlo, zhi, sgn = qz, pz, -coef
    i0 = _first_row(zlo, rowmap, row_z, first)
    if i0 >= row_z.shape[0] or row_z[i0] >= zhi:
        return  # no row centre in [zlo, zhi): the common case for short contour edges
    i1 = _first_row(zhi, rowmap, row_z, i0)
    _add_crossings(px, pz, qx, qz, i0, i1, sgn, row_z, row_x0, row_dx, diff, box)


@njit(cache=True, inline="always")
def _add_crossings(px, pz, qx, qz, i0, i1, sgn, row_z, row_x0, row_dx, diff, box):
    """Add ``sgn`` where edge P->Q crosses rows i0..i1-1 (at the first pixel centre right of it); grow ``box``."""
    n = diff.shape[1]
    slope = (qx - px) / (qz - pz)
    cmin = box[2]
    cmax = box[3]
    for i in range(i0, i1):
        x = px + (row_z[i] - pz) * slope
        jc = (x - row_x0[i]) / row_dx[i]
        if jc >= n - 1:
            continue  # every pixel centre of this row is left of the crossing
        if jc < -1.0:
            idx = 0
        else:
            idx = int(math.floor(jc)) + 1
        diff[i, idx] += sgn
        if idx < cmin:
            cmin = idx
        if idx > cmax:
            cmax = idx
    box[2] = cmin
    box[3] = cmax
    if i0 < box[0]:
        box[0] = i0
    if i1 - 1 > box[1]:
        box[1] = i1 - 1


@njit(cache=True, inline="always")
def _scan_edge_rows(px, pz, ka, qx, qz, kb, coef, row_z, row_x0, row_dx, diff, box):
    """Like :func:`_scan_edge` with each endpoint's first row at or beyond it (ka, kb) known.

    The crossed rows depend only on each endpoint's own index, so edges that
    share a vertex always agree on it (closed outlines stay closed).
    """
    if ka == kb:
        return
    if ka < kb:
        i0, i1, sgn = ka, kb, coef
    else:
        i0, i1, sgn = kb, ka, -coef
    _add_crossings(px, pz, qx, qz, i0, i1, sgn, row_z, row_x0, row_dx, diff, box)


@njit(cache=True)
def _resolve(diff, box, out):
    """Running sums of ``diff`` over the touched box; ``out += (sum != 0)``; clears ``diff``.

    ``box`` = [row min, row max, column min, column max] of the touched entries;
    right of column max a row's sum is constant.
    """
    n = diff.shape[1]
    for i in range(box[0], box[1] + 1):
        run = 0
        for j in range(box[2], box[3] + 1):
            run += diff[i, j]
            diff[i, j] = 0
            out[i, j] += run != 0
        if run != 0:
            for j in range(box[3] + 1, n):
                out[i, j] += 1
    box[0] = diff.shape[0]
    box[1] = -1
    box[2] = n
    box[3] = -1


@njit(cache=True, inline="always")
def _sign(x: float) -> int:
    return 1 if x > 0.0 else (-1 if x < 0.0 else 0)


def kernel_args(verts, normals, topo, rows, dirs, n: int) -> tuple:
    """:func:`occlusion_counts`' arguments (without ``stage``) from a mesh's vertices and face normals, its
    topology, a view's ground rows (:func:`ground_rows`) and directions (T, S, 3), and the frame size."""
    return (
        verts,
        normals,
        topo.edges,
        topo.ptr,
        topo.inc_face,
        topo.inc_dir,
        dirs,
        rows.z,
        rows.x0,
        rows.dx,
        rows.rowmap,
        rows.first,
        n,
    )


@njit(cache=True)
def _face_norms(normals):
    """|n_f| per face."""
    norms = np.empty(normals.shape[0])
    for f in range(normals.shape[0]):
        norms[f] = math.sqrt(normals[f, 0] ** 2 + normals[f, 1] ** 2 + normals[f, 2] ** 2)
    return norms


@njit(cache=True, inline="always")
def _direction_cone(dirs):
    """The mean (cx, cy, cz) of a texel's directions ``dirs`` (S, 3) and a radius about it that holds them all."""
    s_count = dirs.shape[0]
    cx, cy, cz = 0.0, 0.0, 0.0
    for s in range(s_count):
        cx += dirs[s, 0]
        cy += dirs[s, 1]
        cz += dirs[s, 2]
    cx, cy, cz = cx / s_count, cy / s_count, cz / s_count
    radius = 0.0
    for s in range(s_count):
        d2 = (dirs[s, 0] - cx) ** 2 + (dirs[s, 1] - cy) ** 2 + (dirs[s, 2] - cz) ** 2
        radius = max(radius, math.sqrt(d2))
    return cx, cy, cz, radius * (1.0 + 1e-9) + 1e-12


@njit(cache=True, inline="always")
def _sample_signs(nx, ny, nz, dirs, row):
    """sign(n . w) of every direction w in ``dirs`` (S, 3) into ``row``; their common value, else MIXED."""
    c0 = _sign(nx * dirs[0, 0] + ny * dirs[0, 1] + nz * dirs[0, 2])
    row[0] = c0
    same = True
    for s in range(1, dirs.shape[0]):
        cs = _sign(nx * dirs[s, 0] + ny * dirs[s, 1] + nz * dirs[s, 2])
        row[s] = cs
        same = same and cs == c0
    return c0 if same else MIXED


@njit(cache=True)
def _face_signs(normals, norms, dirs):
    """Each face's sign(n_f . w) over a texel's directions ``dirs`` (S, 3): ``code`` +1 / -1 / 0 when all samples
    agree, else MIXED with the per-sample signs in row ``slot[f]`` of ``signs``.

    One dot product with the mean direction settles a face when the samples' spread cannot change its sign.
    """
    nf = normals.shape[0]
    code = np.empty(nf, np.int8)
    slot = np.empty(nf, np.int64)
    signs = np.empty((nf, dirs.shape[0]), np.int8)
    cx, cy, cz, radius = _direction_cone(dirs)
    n_signs = 0
    for f in range(nf):
        nx, ny, nz = normals[f, 0], normals[f, 1], normals[f, 2]
        nn = norms[f]
        dc = nx * cx + ny * cy + nz * cz
        if nn == 0.0:
            code[f] = 0
        elif dc > nn * radius:
            code[f] = 1
        elif dc < -nn * radius:
            code[f] = -1
        else:
            code[f] = _sample_signs(nx, ny, nz, dirs, signs[n_signs])
            if code[f] == MIXED:
                slot[f] = n_signs
                n_signs += 1
    return code, slot, signs


@njit(cache=True, inline="always")
def _settled_coefficient(e, ptr, inc_face, inc_dir, code):
    """c_e summed over the edge's settled faces, and whether a MIXED face touches it."""
    coef = 0
    is_mixed = False
    for k in range(ptr[e], ptr[e + 1]):
        cf = code[inc_face[k]]
        if cf == MIXED:
            is_mixed = True
        else:
            coef += cf * inc_dir[k]
    return coef, is_mixed


@njit(cache=True, inline="always")
def _sample_coefficients(e, settled, ptr, inc_face, inc_dir, code, slot, signs, row):
    """c_e per sample into ``row``: ``settled`` plus the MIXED faces' per-sample terms."""
    for s in range(row.shape[0]):
        row[s] = settled
    for k in range(ptr[e], ptr[e + 1]):
        f = inc_face[k]
        if code[f] == MIXED:
            for s in range(row.shape[0]):
                row[s] += signs[slot[f], s] * inc_dir[k]


@njit(cache=True)
def _edge_coefficients(n_edges, ptr, inc_face, inc_dir, code, slot, signs):
    """The edges that can cast shadow under a texel: ``fixed`` with their one non-zero coefficient, and ``mixed``
    (touching a MIXED face) with one coefficient per sample. Edges with coefficient 0 everywhere cancel."""
    s_count = signs.shape[1]
    fixed = np.empty(n_edges, np.int32)
    fixed_coef = np.empty(n_edges, np.int32)
    mixed = np.empty(n_edges, np.int32)
    mixed_coef = np.empty((n_edges, s_count), np.int32)
    n_fixed = 0
    n_mixed = 0
    for e in range(n_edges):
        coef, is_mixed = _settled_coefficient(e, ptr, inc_face, inc_dir, code)
        if is_mixed:
            _sample_coefficients(e, coef, ptr, inc_face, inc_dir, code, slot, signs, mixed_coef[n_mixed])
            mixed[n_mixed] = e
            n_mixed += 1
        elif coef != 0:
            fixed[n_fixed] = e
            fixed_coef[n_fixed] = coef
            n_fixed += 1
    return fixed[:n_fixed], fixed_coef[:n_fixed], mixed[:n_mixed], mixed_coef[:n_mixed]


@njit(cache=True, inline="always")
def _project_vertex(a, s, kx, kz, verts, ground, ground_row, stamp, rowmap, row_z, first):
    """Vertex a's projection onto the ground along direction s: (x, z) and its first row at or beyond z.

    ``stamp`` holds the direction each vertex was last projected for, so a vertex is projected once per direction.
    """
    if stamp[a] != s:
        stamp[a] = s
        ground[a, 0] = verts[a, 0] - kx * verts[a, 1]
        ground[a, 1] = verts[a, 2] - kz * verts[a, 1]
        ground_row[a] = _first_row(ground[a, 1], rowmap, row_z, first)


@njit(cache=True, inline="always")
def _edge_at(m, s, fixed, fixed_coef, mixed, mixed_coef):
    """The m-th counting edge (fixed ones first) and its coefficient for direction s (0: it casts nothing)."""
    if m < fixed.shape[0]:
        return fixed[m], fixed_coef[m]
    m -= fixed.shape[0]
    return mixed[m], mixed_coef[m, s]


# Inlined into occlusion_counts' parallel loop: compiled as a function of its own, its vertex projection
# loop ran about twice as slow.
@njit(cache=True, inline="always")
def _scan_texel(verts, edges, dirs, fixed, fixed_coef, mixed, mixed_coef, rows, first, scan, out):
    """Per direction of the texel: project the counting edges' vertices onto the ground, and with ``scan``
    scan-convert the edges and add the running sums' shadowed pixels to ``out`` (n, n).

    ``rows`` = (row_z, row_x0, row_dx, rowmap) of :class:`GroundRows`.
    """
    row_z, row_x0, row_dx, rowmap = rows
    n = out.shape[0]
    nv = verts.shape[0]
    diff = np.zeros((n, n), np.int32)
    box = np.array([n, -1, n, -1], np.int64)
    ground = np.empty((nv, 2))
    ground_row = np.empty(nv, np.int64)
    stamp = np.full(nv, -1, np.int64)
    for s in range(dirs.shape[0]):
        kx = dirs[s, 0] / dirs[s, 1]
        kz = dirs[s, 2] / dirs[s, 1]
        for m in range(fixed.shape[0] + mixed.shape[0]):
            e, coef = _edge_at(m, s, fixed, fixed_coef, mixed, mixed_coef)
            if coef == 0:
                continue
            a = edges[e, 0]
            b = edges[e, 1]
            _project_vertex(a, s, kx, kz, verts, ground, ground_row, stamp, rowmap, row_z, first)
            _project_vertex(b, s, kx, kz, verts, ground, ground_row, stamp, rowmap, row_z, first)
            if scan:
                xa, za, xb, zb = ground[a, 0], ground[a, 1], ground[b, 0], ground[b, 1]
                _scan_edge_rows(xa, za, ground_row[a], xb, zb, ground_row[b], coef, row_z, row_x0, row_dx, diff, box)
        if scan:
            _resolve(diff, box, out)


@njit(cache=True, parallel=True)
def occlusion_counts(
    verts, normals, edges, ptr, inc_face, inc_dir, dirs, row_z, row_x0, row_dx, rowmap, first, n, stage=3
):
    """Per texel and pixel, how many of the texel's directions are blocked: (T, n, n) uint8.

    ``dirs`` (T, S, 3) world directions with positive y, S <= 255. Per texel, a
    face's sign is settled by one dot product with the texel's mean direction
    when the samples' spread cannot change it, else per sample; edges whose
    coefficient is the same non-zero value for every sample are scanned
    directly, edges touching an undecided face get one coefficient per sample.
    ``stage`` < 3 stops early, for timing: 1 after the per-texel tables, 2
    before scan conversion (the result is then incomplete).
    """
    out = np.zeros((dirs.shape[0], n, n), np.uint8)
    norms = _face_norms(normals)
    rows = (row_z, row_x0, row_dx, rowmap)
    for t in prange(dirs.shape[0]):
        code, slot, signs = _face_signs(normals, norms, dirs[t])
        fixed, fixed_coef, mixed, mixed_coef = _edge_coefficients(
            edges.shape[0], ptr, inc_face, inc_dir, code, slot, signs
        )
        if stage >= 2:
            _scan_texel(verts, edges, dirs[t], fixed, fixed_coef, mixed, mixed_coef, rows, first, stage >= 3, out[t])
    return out


@njit(cache=True)
def coverage_grid(px, py, face_sign, edges, ptr, inc_face, inc_dir, rows, cols, ss):
    """Point-sampled union of 2D triangles on a (rows*ss, cols*ss) grid of sample centres.

    Vertices (px, py) are in pixel units (col, row); ``face_sign`` is each
    triangle's orientation sign. Returns the grid as uint8 0/1.
    """
    n_rows, n_cols = rows * ss, cols * ss
    row_y = (np.arange(n_rows) + 0.5) / ss
    row_x0 = np.full(n_rows, 0.5 / ss)
    row_dx = np.full(n_rows, 1.0 / ss)
    rowmap = np.array([0.0, -float(ss), 0.0, 1.0, 1.0, 0.0])
    diff = np.zeros((n_rows, n_cols), np.int32)
    box = np.array([n_rows, -1, n_cols, -1], np.int64)
    out = np.zeros((n_rows, n_cols), np.uint8)
    for e in range(edges.shape[0]):
        coef = 0
        for k in range(ptr[e], ptr[e + 1]):
            coef += face_sign[inc_face[k]] * inc_dir[k]
        if coef != 0:
            a, b = edges[e, 0], edges[e, 1]
            _scan_edge(px[a], py[a], px[b], py[b], coef, row_y, row_x0, row_dx, rowmap, 0, diff, box)
    _resolve(diff, box, out)
    return out


@njit(cache=True, parallel=True)
def weighted_sum(counts, weights):
    """sum_t weights[t] * counts[t], (n, n) float64."""
    t_count, n = counts.shape[0], counts.shape[1]
    out = np.zeros((n, n))
    for i in prange(n):
        for t in range(t_count):
            w = weights[t]
            for j in range(n):
                out[i, j] += w * counts[t, i, j]
    return out


@dataclass
class ViewRender:
    """One rendered view: occlusion counts per texel (of ``samples``), AO map, mask, camera."""

    counts: np.ndarray  # (Hb, 2Hb, N, N) uint8, hits out of ``samples``
    samples: int
    ao: np.ndarray  # (N, N) float32, A^(1/3)
    mask: np.ndarray  # (N, N) float32 coverage
    camera: Camera


def mask_coverage(vertices: np.ndarray, faces: np.ndarray, topo: Topology, camera: Camera, ss: int) -> np.ndarray:
    """Object coverage of every pixel, from ss x ss point samples per pixel, (N, N) float32."""
    uv = camera.project(vertices)
    p = uv[faces]
    cross = (p[:, 1, 0] - p[:, 0, 0]) * (p[:, 2, 1] - p[:, 0, 1]) - (p[:, 1, 1] - p[:, 0, 1]) * (
        p[:, 2, 0] - p[:, 0, 0]
    )
    sign = np.sign(cross).astype(np.int8)
    n = camera.n
    grid = coverage_grid(
        np.ascontiguousarray(uv[:, 0]),
        np.ascontiguousarray(uv[:, 1]),
        sign,
        topo.edges,
        topo.ptr,
        topo.inc_face,
        topo.inc_dir,
        n,
        n,
        ss,
    )
    return grid.reshape(n, ss, n, ss).mean(axis=(1, 3), dtype=np.float32)


def view_camera(vertices: np.ndarray, n: int, fov: float, pitch: float) -> Camera:
    """The conventions' camera for already yawed, normalised vertices, framed to the top margin."""
    height = 0.5 * (vertices[:, 1].min() + vertices[:, 1].max())
    return Camera(n, height, fov=fov, pitch=pitch).frame_top(vertices)


def render_view(
    mesh: Mesh,
    topo: Topology,
    yaw: float,
    pitch: float,
    fov: float,
    n: int,
    elm_rows: int,
    samples: int,
    rng: np.random.Generator,
    mask_ss: int | None = None,
) -> ViewRender:
    """Render one view of a normalised mesh: occlusion counts, AO and mask."""
    v = np.ascontiguousarray(yawed(mesh.vertices, yaw))
    cam = view_camera(v, n, fov, pitch)
    rows = ground_rows(cam)
    dirs = cam.to_world(stratified_directions(elm_rows, samples, rng))
    dirs = np.ascontiguousarray(dirs.reshape(-1, samples, 3))
    counts = occlusion_counts(*kernel_args(v, face_normals(v, mesh.faces), topo, rows, dirs, n))
    w = (texel_weights(elm_rows) / np.pi / samples).reshape(-1)
    a = np.clip(1.0 - weighted_sum(counts, w), 0.0, 1.0)
    ss = mask_ss or max(4, -(-1024 // n))
    mask = mask_coverage(v, mesh.faces, topo, cam, ss)
    return ViewRender(counts.reshape(elm_rows, 2 * elm_rows, n, n), samples, np.cbrt(a).astype(np.float32), mask, cam)


def set_threads(k: int) -> None:
    """Threads numba may use in the parallel kernels."""
    most = numba.config.NUMBA_NUM_THREADS  # pyright: ignore[reportPrivateImportUsage, reportAttributeAccessIssue]
    numba.set_num_threads(max(1, min(k, most)))


__all__ = [
    "GroundRows",
    "ViewRender",
    "ground_rows",
    "occlusion_counts",
    "coverage_grid",
    "mask_coverage",
    "render_view",
    "view_camera",
    "weighted_sum",
    "set_threads",
    "topology",
]
