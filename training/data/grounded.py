"""Procedural objects with flat parts lying on the ground around them: what an outline reads as raised.

A computer mouse's cord trailing behind it, a vase on a rug, a spider's legs splayed to the ground, tools among
boards and sticks: seen from above, each flat part lies behind or beside the object in the image and, from its
outline alone, looks like a back or a raised head. Each item is a body (:func:`body`: a low rounded lump, an
upright post with a cap, or a stack of primitives) with its ground parts, one family of :data:`KINDS`:

- ``cord``: a cord (a chain of thin ellipsoids) wandering on the ground from the body's back, or wound there in
  a bundle of loops;
- ``mat``: the body standing on a plate or a cloth larger than its footprint, off its centre;
- ``sprawl``: a small body held up by four to eight legs, each from the body over a knee to a foot far out on the
  ground (a spider, its body on the ground or held high), or lying flat along it (a starfish);
- ``litter``: thin boards, sheets and sticks lying around the body.

Seeded like the other generated sources: each item records its seed, so :func:`build` rebuilds the same mesh.
World units, y up, lowest point at y = 0 (before normalising).
"""

from __future__ import annotations

import numpy as np

from .items import Item, generated_item
from .meshes import Mesh
from .procedural import box, cylinder, merge, random_part, rotate_y, uv_sphere
from .quadrupeds import ellipsoid

KINDS = ("cord", "mat", "sprawl", "litter")


def body(rng: np.random.Generator, base: float = 0.0) -> Mesh:
    """A seeded object standing at height ``base``, centred on x = z = 0: a low rounded lump (a mouse, a stone, a
    shoe), an upright post with a cap (a lamp, a bottle), or a stack of primitives."""
    u = rng.uniform
    kind = rng.integers(3)
    if kind == 0:
        length, height = u(0.2, 0.5), u(0.04, 0.15)
        return ellipsoid((-length / 2, base + height, 0), (length / 2, base + height, 0), height, u(0.05, 0.2))
    if kind == 1:
        r, h = u(0.04, 0.15), u(0.2, 0.8)
        cap = u(0.05, 0.2)
        if rng.random() < 0.5:
            top = uv_sphere(cap, (0, base + h + cap * 0.8, 0), 12, 24)
        else:
            top = box((cap * 2, cap, cap * 2), (0, base + h + cap / 2, 0))
        return merge([cylinder(r, h, 24, (0, base, 0)), top])
    parts, y = [], base
    for _ in range(rng.integers(2, 4)):
        p = random_part(rng, y)
        parts.append(p)
        y = p.vertices[:, 1].max() * u(0.6, 1.0)
    mesh = merge(parts)
    return Mesh(mesh.vertices - [mesh.vertices[:, 0].mean(), 0.0, mesh.vertices[:, 2].mean()], mesh.faces)


def _path(
    start: np.ndarray, heading: float, steps: int, step: float, wander: float, rng: np.random.Generator
) -> np.ndarray:
    """A random walk on the ground from ``start`` (x, z), turning by up to ``wander`` radians a step."""
    points = [np.asarray(start, float)]
    for _ in range(steps):
        heading += rng.uniform(-wander, wander)
        points.append(points[-1] + step * np.array([np.cos(heading), np.sin(heading)]))
    return np.array(points)


def _coil(start: np.ndarray, rng: np.random.Generator) -> np.ndarray:
    """A cord wound in two to four loops on the ground, each an ellipse of its own size about a centre behind
    ``start`` (x, z), as a cable bundled and laid down."""
    u = rng.uniform
    radius = u(0.04, 0.12)
    centre = start + [-radius * u(1.0, 1.5), u(-0.5, 0.5) * radius]
    turn = u(0, np.pi)
    points = []
    for _ in range(int(rng.integers(2, 5))):
        a, b = radius * u(0.7, 1.3), radius * u(0.3, 1.0)
        t = np.linspace(0, 2 * np.pi, 13)[:-1] + turn
        points.append(np.stack([a * np.cos(t), b * np.sin(t)], 1) + centre + u(-0.3, 0.3, 2) * radius)
    return np.concatenate(points)


def _footprint(mesh: Mesh) -> float:
    """The radius of ``mesh``'s footprint about the y axis."""
    return float(np.hypot(mesh.vertices[:, 0], mesh.vertices[:, 2]).max())


def generate(kind: str, seed: int) -> Mesh:
    """A seeded object of one family (:data:`KINDS`) with its parts on the ground."""
    rng = np.random.default_rng([seed, KINDS.index(kind), 23])
    u = rng.uniform
    if kind == "cord":
        main = body(rng)
        r = u(0.005, 0.02)
        back = main.vertices[:, 0].min()
        path = _path(
            np.array([back + 2 * r, 0.0]), np.pi + u(-0.5, 0.5), int(rng.integers(6, 17)), u(0.04, 0.12), 0.7, rng
        )
        if rng.random() < 0.4:  # the rest of the cord wound in a bundle of loops behind the body
            path = np.concatenate([path[:3], _coil(path[2], rng)])
        cord = [ellipsoid((a[0], r, a[1]), (b[0], r, b[1]), r) for a, b in zip(path[:-1], path[1:], strict=True)]
        return merge([main, *cord])
    if kind == "mat":
        thick = u(0.004, 0.04)
        main = body(rng, thick)
        reach = _footprint(main) * u(1.3, 2.5)
        if rng.random() < 0.5:
            plate = box((2 * reach, thick, 2 * reach * u(0.6, 1.0)), (0, thick / 2, 0))
            plate = rotate_y(plate, u(0, np.pi))
        else:
            plate = cylinder(reach, thick, 48)
        shift = u(0.2, 0.6) * reach * np.array([np.cos(a := u(0, 2 * np.pi)), 0.0, np.sin(a)])
        return merge([Mesh(main.vertices + shift, main.faces), plate])
    if kind == "sprawl":
        flat = rng.random() < 0.3  # a starfish's legs lie along the ground; a spider's rise over a knee
        r_body = u(0.05, 0.15)
        lift = 0.0 if flat else u(0.0, 0.45)  # a spider's body from on the ground to held high on its legs
        centre = np.array([0.0, lift + r_body, 0.0])
        parts = [ellipsoid(centre - [r_body * u(1, 2), 0, 0], centre + [r_body * u(1, 2), 0, 0], r_body)]
        leg_r = u(0.005, 0.02)
        n = int(rng.integers(4, 9))
        for a in 2 * np.pi * (np.arange(n) + u(-0.3, 0.3, n)) / n:
            out = np.array([np.cos(a), 0.0, np.sin(a)])
            reach = u(0.3, 0.7)
            hip = centre + out * r_body * 0.8
            foot = out * reach + [0.0, leg_r, 0.0]
            if flat:
                hip[1] = leg_r
                parts.append(ellipsoid(hip, foot, leg_r * u(1.5, 3.0)))
            else:
                knee = out * reach * u(0.3, 0.6) + [0.0, centre[1] + u(0.0, 0.25), 0.0]
                parts += [ellipsoid(hip, knee, leg_r * 1.3), ellipsoid(knee, foot, leg_r)]
        return merge(parts)
    if kind == "litter":
        main = body(rng)
        parts = [main]
        near = _footprint(main)
        for _ in range(rng.integers(2, 7)):
            at = u(1.0, 3.0) * near + 0.05
            a = u(0, 2 * np.pi)
            length, width, thick = u(0.1, 0.6), u(0.01, 0.3), u(0.004, 0.03)
            piece = box((length, thick, width), (0, thick / 2, 0))
            piece = rotate_y(piece, u(0, np.pi))
            parts.append(Mesh(piece.vertices + [at * np.cos(a), 0.0, at * np.sin(a)], piece.faces))
        return merge(parts)
    raise ValueError(f"unknown grounded kind {kind!r}")


def grounded_items(count: int, seed: int) -> list[Item]:
    """``count`` items cycling through the families; split by item index (80/10/10), every split holding every
    family (the cycle steps on by one every ten items)."""
    kinds = [KINDS[(i + i // 10) % len(KINDS)] for i in range(count)]
    return [
        generated_item("grounded", "ground", "kind", kind, "animal" if kind == "sprawl" else "object", seed, i)
        for i, kind in enumerate(kinds)
    ]


def build(params: dict) -> Mesh:
    return generate(params["kind"], params["seed"])
