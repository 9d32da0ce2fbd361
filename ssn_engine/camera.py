"""The pinhole camera of ``docs/conventions.md``.

World: right-handed, y up, ground y = 0. The camera's horizontal forward
vector is f = (0, 0, -1) and its right vector r = (1, 0, 0); it looks at
T = (0, c, 0) from distance 2, pitched down by ``pitch`` degrees. Image
coordinates are continuous (col, row) with pixel (i, j) covering
[j, j + 1) x [i, i + 1); a vertical lens shift moves the object's top to row
round(0.03 N).
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field

import numpy as np

from .host_kit.camera_rules import DEFAULT_FOV

DISTANCE = 2.0
TOP_MARGIN = 0.03
DEFAULT_PITCH = 15.0
SPAN_TOLERANCE = 1e-9  # relative: a card's fit stops once its span is this near the rows it must span
PITCH_RANGE = (-10.0, 80.0)  # pitches :func:`camera_for_span` searches; a horizon beyond them is clamped

RIGHT = np.array([1.0, 0.0, 0.0])
UP = np.array([0.0, 1.0, 0.0])
FORWARD = np.array([0.0, 0.0, -1.0])


def top_row(n: int) -> int:
    """The frame row that holds the object's topmost pixel."""
    return int(round(TOP_MARGIN * n))


@dataclass
class Camera:
    """Pinhole camera looking at (0, target_height, 0); ``shift`` is the lens shift in rows."""

    n: int
    target_height: float
    fov: float = DEFAULT_FOV
    pitch: float = DEFAULT_PITCH
    shift: float = 0.0
    view: np.ndarray = field(init=False)
    up: np.ndarray = field(init=False)
    centre: np.ndarray = field(init=False)
    focal: float = field(init=False)

    def __post_init__(self) -> None:
        p = np.radians(self.pitch)
        self.view = np.cos(p) * FORWARD - np.sin(p) * UP
        self.up = np.array([0.0, -self.view[2], self.view[1]])  # RIGHT x view; np.cross costs more than a card's fit
        self.centre = np.array([0.0, self.target_height, 0.0]) - DISTANCE * self.view
        self.focal = 0.5 * self.n / np.tan(np.radians(self.fov) / 2)

    def project(self, points: np.ndarray) -> np.ndarray:
        """World points (..., 3) to continuous image coordinates (..., 2) as (col, row)."""
        points = np.asarray(points, np.float64)
        return np.stack(self.project_xyz(points[..., 0], points[..., 1], points[..., 2]), axis=-1)

    def project_xyz(self, x: np.ndarray, y: np.ndarray, z: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """Like :meth:`project` for coordinates given as separate arrays; returns (col, row)."""
        c, v, u = (tuple(float(a) for a in vec) for vec in (self.centre, self.view, self.up))  # keep x's dtype
        rx, ry, rz = x - c[0], y - c[1], z - c[2]
        depth = rx * v[0] + ry * v[1] + rz * v[2]
        up = rx * u[0] + ry * u[1] + rz * u[2]
        f, half = float(self.focal), 0.5 * self.n
        col = half + f * rx / depth  # RIGHT is the x axis
        row = half - f * up / depth + float(self.shift)
        return col, row

    def frame_top(self, points: np.ndarray) -> Camera:
        """Set the lens shift so that the highest projected point lies on row round(0.03 N)."""
        self.shift = 0.0
        self.shift = top_row(self.n) - float(self.project(points)[..., 1].min())
        return self

    def ray_matrix(self) -> np.ndarray:
        """(3, 3): an image point (col, row, 1) to the world direction through it, scaled to a unit camera depth
        (a point at depth t along it is ``centre + t * direction``)."""
        f, half = float(self.focal), 0.5 * self.n
        origin = self.view - half / f * RIGHT + (half + float(self.shift)) / f * self.up
        return np.stack([RIGHT / f, -self.up / f, origin], axis=1)

    def rays(self, cols: np.ndarray | float, rows: np.ndarray | float) -> np.ndarray:
        """World directions (..., 3) through image points (``cols``, ``rows``, broadcast together), as
        :meth:`ray_matrix` gives them."""
        c, r = np.broadcast_arrays(np.asarray(cols, np.float64), np.asarray(rows, np.float64))
        return np.stack([c, r, np.ones_like(c)], axis=-1) @ self.ray_matrix().T

    def pixel_rays(self) -> np.ndarray:
        """Unnormalised world directions (N, N, 3) through every pixel centre."""
        centres = np.arange(self.n) + 0.5
        return self.rays(centres[None, :], centres[:, None])

    def projection(self) -> np.ndarray:
        """(3, 4): a world point (x, y, z, 1) to its image point (col, row, 1) times its camera depth."""
        f, half = float(self.focal), 0.5 * self.n
        rows = np.stack(
            [f * RIGHT + half * self.view, -f * self.up + (half + float(self.shift)) * self.view, self.view]
        )
        return np.concatenate([rows, -(rows @ self.centre)[:, None]], axis=1)

    def ground_points(self) -> tuple[np.ndarray, np.ndarray]:
        """Ground points (N, N, 3) seen through each pixel, and where the ray reaches the ground."""
        rays = self.pixel_rays()
        down = rays[..., 1] < -1e-9
        t = np.where(down, -self.centre[1] / np.where(down, rays[..., 1], -1.0), 0.0)
        return self.centre + t[..., None] * rays, down

    @property
    def horizon(self) -> float:
        """The horizon row h (conventions, "Camera input"): where a level ray lands, shift included."""
        return horizon_row(self.n, float(self.focal), self.pitch, self.shift)

    def to_world(self, camera_basis: np.ndarray) -> np.ndarray:
        """Directions from the ELM's camera basis (right, up, forward) to world coordinates."""
        return camera_basis[..., :1] * RIGHT + camera_basis[..., 1:2] * UP + camera_basis[..., 2:] * FORWARD


def horizon_row(n: float, focal: float, pitch: float, shift: float) -> float:
    """The conventions' horizon row h = N/2 - f tan(pitch) + shift (frame pixels; pitch in degrees)."""
    return 0.5 * n - focal * float(np.tan(np.radians(pitch))) + shift


def focal_from_fov(n: float, fov: float) -> float:
    """Focal length in pixels of a vertical field of view ``fov`` (degrees) over ``n`` rows."""
    return 0.5 * n / float(np.tan(np.radians(fov) / 2))


def fov_from_focal(n: float, focal: float) -> float:
    """Vertical field of view (degrees) of a focal length ``focal`` (pixels) over ``n`` rows."""
    return float(np.degrees(2 * np.arctan(0.5 * n / focal)))


def _axis_row(cam: Camera, y: float, target: float | None = None) -> float:
    """The unshifted image row of the point (0, y, 0), seen by ``cam`` or, given ``target``, by ``cam`` looking at
    (0, ``target``, 0) instead (scalar arithmetic: the fit below calls it often)."""
    ry, rz = y - _centre_height(cam, target), -float(cam.centre[2])
    depth = ry * float(cam.view[1]) + rz * float(cam.view[2])
    up = ry * float(cam.up[1]) + rz * float(cam.up[2])
    return 0.5 * cam.n - float(cam.focal) * up / depth


def _centre_height(cam: Camera, target: float | None) -> float:
    """The height of ``cam``'s centre, or of its centre looking at (0, ``target``, 0) (as :class:`Camera` places
    it)."""
    return float(cam.centre[1]) if target is None else target - DISTANCE * float(cam.view[1])


def _fit_span(n: int, fov: float, pitch: float, top: float, base: float) -> Camera | None:
    """The camera of a vertical card standing at the origin whose projection spans rows [top, base):
    its height found by fixed-point iteration, the lens shift putting its foot on row ``base``. None where no
    card does (a camera looking so steeply down through so wide a lens that the card's top would lie behind it)."""
    aim = Camera(n, 0.0, fov=fov, pitch=pitch)  # its view and focal length; it looks at each height tried
    height, span, fitted = 0.5, None, 0.5
    for _ in range(12):
        fitted = height
        span = _span(aim, height, height / 2)
        if span is None or abs(span - (base - top)) <= SPAN_TOLERANCE * (base - top):
            break
        height *= (base - top) / span
    if span is None or abs(span - (base - top)) > 0.01 * (base - top):  # no card, or the iteration found none
        return None
    cam = Camera(n, fitted / 2, fov=fov, pitch=pitch)
    cam.shift = base - _axis_row(cam, 0.0)
    return cam


def _span(cam: Camera, height: float, target: float | None = None) -> float | None:
    """Rows from the top to the foot of a card ``height`` tall, seen by ``cam`` (looking at (0, ``target``, 0)
    where given), or None where its top or foot is not in front of the camera (or the card shows upside down)."""
    centre_y = _centre_height(cam, target)
    for y in (0.0, height):
        ry, rz = y - centre_y, -float(cam.centre[2])
        if ry * float(cam.view[1]) + rz * float(cam.view[2]) <= 1e-6:
            return None
    span = _axis_row(cam, 0.0, target) - _axis_row(cam, height, target)
    return span if math.isfinite(span) and span > 0 else None


def camera_for_span(
    n: int, top: float, base: float, horizon: float | None = None, focal: float | None = None
) -> tuple[Camera, float]:
    """The conventions' camera for an upright card spanning frame rows [top, base), and its height.

    Without a camera input it uses the default field of view and pitch. With the horizon row ``horizon`` and
    the focal length ``focal`` (frame pixels, conventions "Camera input") the field of view follows from the
    focal length and the pitch is searched (bisection; the horizon rises monotonically with the pitch) so that
    the card's horizon lands on ``horizon``. A horizon the pitches of ``PITCH_RANGE`` cannot reach (at or
    below the card's foot: a camera under the ground) gets the nearest pitch of that range.
    """
    if horizon is None or focal is None:
        cam = _fit_span(n, DEFAULT_FOV, DEFAULT_PITCH, top, base)
        assert cam is not None  # the default camera always fits
        return cam, 2 * cam.target_height
    fov = fov_from_focal(n, focal)
    lo, hi = PITCH_RANGE  # horizon(lo) > horizon(hi)
    for _ in range(24):  # 90 degrees / 2^24: well below a pixel
        mid = 0.5 * (lo + hi)
        fit = _fit_span(n, fov, mid, top, base)
        if fit is not None and fit.horizon > horizon:
            lo = mid
        else:  # too high a horizon, or too steep a pitch for any card to span the rows: look less steeply down
            hi = mid
    cam = _fit_span(n, fov, 0.5 * (lo + hi), top, base) or _fit_span(n, fov, lo, top, base)
    if cam is None:
        raise ValueError(f"no camera with a {fov:.0f} degree field of view frames this cutout")
    return cam, 2 * cam.target_height
