"""Per-pixel depth of a mesh seen through a camera: the nearest and the farthest surface along each pixel centre's
ray (a z-buffer that keeps both ends), the geometry a proxy with thickness needs."""

from __future__ import annotations

import numba
import numpy as np

from ssn_engine.camera import Camera


@numba.njit(cache=True)
def _raster(cols, rows, inv_depth, faces, n, front, back):  # pragma: no cover - numba
    for f in range(faces.shape[0]):
        a, b, c = faces[f, 0], faces[f, 1], faces[f, 2]
        if inv_depth[a] <= 0 or inv_depth[b] <= 0 or inv_depth[c] <= 0:
            continue  # behind the camera (never in the dataset's framing)
        x0, y0, x1, y1, x2, y2 = cols[a], rows[a], cols[b], rows[b], cols[c], rows[c]
        area = (x1 - x0) * (y2 - y0) - (y1 - y0) * (x2 - x0)
        if abs(area) < 1e-12:
            continue
        lo_x = max(int(np.floor(min(x0, x1, x2) - 0.5)), 0)
        hi_x = min(int(np.ceil(max(x0, x1, x2) - 0.5)), n - 1)
        lo_y = max(int(np.floor(min(y0, y1, y2) - 0.5)), 0)
        hi_y = min(int(np.ceil(max(y0, y1, y2) - 0.5)), n - 1)
        for i in range(lo_y, hi_y + 1):
            py = i + 0.5
            for j in range(lo_x, hi_x + 1):
                px = j + 0.5
                w0 = ((x1 - px) * (y2 - py) - (y1 - py) * (x2 - px)) / area
                w1 = ((x2 - px) * (y0 - py) - (y2 - py) * (x0 - px)) / area
                w2 = 1.0 - w0 - w1
                if w0 < 0 or w1 < 0 or w2 < 0:
                    continue
                # 1 / depth is affine in the image plane: perspective-correct depth
                d = 1.0 / (w0 * inv_depth[a] + w1 * inv_depth[b] + w2 * inv_depth[c])
                if d < front[i, j]:
                    front[i, j] = d
                if d > back[i, j]:
                    back[i, j] = d


def depth_range(vertices: np.ndarray, faces: np.ndarray, camera: Camera) -> tuple[np.ndarray, np.ndarray]:
    """Depth (along the camera's view axis) of the nearest and the farthest surface at every pixel centre,
    (N, N) float32 each; inf and -inf where the ray misses the object."""
    v = np.asarray(vertices, np.float64)
    rel = v - camera.centre
    depth = rel @ camera.view
    cols, rows = camera.project_xyz(v[:, 0], v[:, 1], v[:, 2])
    n = camera.n
    front = np.full((n, n), np.inf)
    back = np.full((n, n), -np.inf)
    _raster(cols, rows, 1.0 / depth, np.ascontiguousarray(faces, np.int64), n, front, back)
    return front.astype(np.float32), back.astype(np.float32)
