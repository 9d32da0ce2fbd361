"""Procedural rounded objects: what a round outline says nothing about the camera's pitch with.

A stone, a head, a pot, a loaf, a sculpture: seen level or from above, a rounded solid's outline is rounded below
as well as above, where a box's or a cylinder's base is a line seen level and an ellipse's arc seen from above.
An estimator that learnt the camera from bases alone reads every round bottom as a view from above. Each item is
one family of :data:`KINDS`, turned at random and resting on its lowest point:

- ``blob``: two to seven ellipsoids grown from one another (a stone, a lump of clay, an animal curled up);
- ``egg``: one ellipsoid, long or flat, turned at random (an egg, a ball, a loaf, a pebble);
- ``bust``: a large rounded part on a narrower one (a head on a neck, a bust on its socle, a mushroom, a bulb);
- ``vessel``: a wide rounded body with a knob, a handle or a lip (a pot, a jug, a gourd).

Seeded like the other generated sources: each item records its seed, so :func:`build` rebuilds the same mesh.
World units, y up, lowest point at y = 0 (before normalising).
"""

from __future__ import annotations

import numpy as np

from .items import Item, generated_item
from .meshes import Mesh
from .procedural import merge, torus, uv_sphere
from .quadrupeds import ellipsoid

KINDS = ("blob", "egg", "bust", "vessel")


def _turned(mesh: Mesh, rng: np.random.Generator, most: float) -> Mesh:
    """``mesh`` turned about a random horizontal axis by up to ``most`` radians and about y at random, then set
    on the ground (its lowest point at y = 0)."""
    a, b = rng.uniform(0.0, 2.0 * np.pi), rng.uniform(-most, most)
    axis = np.array([np.cos(a), 0.0, np.sin(a)])
    k = np.array([[0.0, -axis[2], axis[1]], [axis[2], 0.0, -axis[0]], [-axis[1], axis[0], 0.0]])
    turn = np.eye(3) + np.sin(b) * k + (1.0 - np.cos(b)) * k @ k  # Rodrigues: a proper rotation
    c, s = np.cos(rng.uniform(0.0, 2.0 * np.pi)), np.sin(rng.uniform(0.0, 2.0 * np.pi))
    yaw = np.array([[c, 0.0, s], [0.0, 1.0, 0.0], [-s, 0.0, c]])
    v = mesh.vertices @ (yaw @ turn).T
    return Mesh(v - [0.0, v[:, 1].min(), 0.0], mesh.faces)


def _radii(rng: np.random.Generator, size: float) -> tuple[float, float, float]:
    """Three semi-axes about ``size``, each 0.5 to 1.5 times it."""
    return tuple(float(x) for x in size * rng.uniform(0.5, 1.5, 3))


def _ellipsoid_at(centre: np.ndarray, radii: tuple[float, float, float]) -> Mesh:
    """An axis-aligned ellipsoid of semi-axes ``radii`` (x, y, z) about ``centre``."""
    unit = uv_sphere(1.0, rings=16, segments=32)
    return Mesh(unit.vertices * np.asarray(radii) + centre, unit.faces)


def generate(kind: str, seed: int) -> Mesh:
    """One seeded object of family ``kind`` (:data:`KINDS`)."""
    rng = np.random.default_rng(seed)
    u = rng.uniform
    if kind == "blob":
        centres = [np.zeros(3)]
        parts = [_ellipsoid_at(centres[0], _radii(rng, 0.3))]
        for _ in range(rng.integers(1, 7)):
            at = centres[rng.integers(len(centres))] + rng.normal(0.0, 0.18, 3)
            centres.append(at)
            parts.append(_ellipsoid_at(at, _radii(rng, u(0.1, 0.3))))
        return _turned(merge(parts), rng, np.pi)
    if kind == "egg":
        return _turned(_ellipsoid_at(np.zeros(3), _radii(rng, 0.3)), rng, np.pi)
    if kind == "bust":
        foot_r, foot_h = u(0.05, 0.2), u(0.05, 0.4)
        head = _radii(rng, u(0.15, 0.35))
        base = ellipsoid((0.0, 0.0, 0.0), (0.0, foot_h, 0.0), foot_r, foot_r * u(0.6, 1.4))
        top = _ellipsoid_at(np.array([0.0, foot_h + head[1] * u(0.6, 0.95), 0.0]), head)
        return _turned(merge([base, top]), rng, u(0.0, 0.5))
    if kind == "vessel":
        rx, ry = u(0.2, 0.4), u(0.12, 0.3)
        rz = rx * u(0.7, 1.0)
        body = _ellipsoid_at(np.array([0.0, ry, 0.0]), (rx, ry, rz))
        parts = [body]
        if rng.random() < 0.6:  # a knob or a lid on top
            knob = u(0.02, 0.08)
            parts.append(uv_sphere(knob, (0.0, 2.0 * ry + knob * 0.5, 0.0), 10, 20))
        if rng.random() < 0.6:  # a handle at the side: a ring standing upright
            parts.append(torus(ry * u(0.4, 0.7), u(0.015, 0.04), (rx, ry * u(0.8, 1.2), 0.0), segments=32, sides=12))
        if rng.random() < 0.5:  # a lip or a spout on the other side
            tip = np.array([-rx * u(1.1, 1.5), ry * u(1.2, 2.0), 0.0])
            parts.append(ellipsoid((-rx * 0.6, ry, 0.0), tip, u(0.02, 0.06)))
        return _turned(merge(parts), rng, u(0.0, 0.3))
    raise ValueError(f"unknown lumps kind {kind!r}")


def lumps_items(count: int, seed: int) -> list[Item]:
    """``count`` items cycling through the families; split by item index (80/10/10), every split holding every
    family (the cycle steps on by one every ten items)."""
    kinds = [KINDS[(i + i // 10) % len(KINDS)] for i in range(count)]
    return [generated_item("lumps", "lump", "kind", kind, "object", seed, i) for i, kind in enumerate(kinds)]


def build(params: dict) -> Mesh:
    return generate(params["kind"], params["seed"])
