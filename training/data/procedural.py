"""Procedural shapes: primitives and seeded compounds (poles, slabs, shapes with holes, stacks).

Each generated item records its generator and seed, so :func:`build` rebuilds
the same mesh. Primitives are closed, consistently oriented triangle meshes
(outward normals), in world units with y up.
"""

from __future__ import annotations

import numpy as np

from .items import Item, generated_item
from .meshes import Mesh

KINDS = ("pole", "slab", "holes", "compound", "arch", "table")


def box(size=(1.0, 1.0, 1.0), centre=(0.0, 0.0, 0.0)) -> Mesh:
    """An axis-aligned box."""
    sx, sy, sz = 0.5 * np.asarray(size, float)
    v = np.array([[x, y, z] for x in (-sx, sx) for y in (-sy, sy) for z in (-sz, sz)]) + np.asarray(centre, float)
    # vertex index = 4 * (x > 0) + 2 * (y > 0) + (z > 0); quads listed counter-clockwise seen from outside
    quads = [(0, 1, 3, 2), (4, 6, 7, 5), (0, 4, 5, 1), (2, 3, 7, 6), (0, 2, 6, 4), (1, 5, 7, 3)]
    f = [(a, b, c) for a, b, c, d in quads] + [(a, c, d) for a, b, c, d in quads]
    return Mesh(v, np.array(f, np.int32))


def cylinder(radius: float, height: float, segments: int = 48, base=(0.0, 0.0, 0.0)) -> Mesh:
    """A closed cylinder on the y axis from base y to base y + height."""
    a = 2 * np.pi * np.arange(segments) / segments
    ring = np.stack([radius * np.cos(a), np.zeros(segments), -radius * np.sin(a)], axis=1)
    top = ring + [0.0, height, 0.0]
    v = np.concatenate([ring, top, [[0, 0, 0], [0, height, 0]]]) + np.asarray(base, float)
    i = np.arange(segments)
    j = (i + 1) % segments
    bottom_c, top_c = 2 * segments, 2 * segments + 1
    side = np.concatenate([np.stack([i, j, j + segments], 1), np.stack([i, j + segments, i + segments], 1)])
    caps = np.concatenate(
        [
            np.stack([np.full(segments, bottom_c), j, i], 1),
            np.stack([np.full(segments, top_c), i + segments, j + segments], 1),
        ]
    )
    return Mesh(v, np.concatenate([side, caps]).astype(np.int32))


def uv_sphere(radius: float, centre=(0.0, 0.0, 0.0), rings: int = 48, segments: int = 96) -> Mesh:
    """A closed UV sphere."""
    theta = np.pi * np.arange(1, rings) / rings
    phi = 2 * np.pi * np.arange(segments) / segments
    st, ct = np.sin(theta)[:, None], np.cos(theta)[:, None]
    body = np.stack([st * np.cos(phi), np.broadcast_to(ct, (rings - 1, segments)), -st * np.sin(phi)], -1)
    v = np.concatenate([[[0, 1, 0]], body.reshape(-1, 3), [[0, -1, 0]]]) * radius + np.asarray(centre, float)
    idx = 1 + np.arange((rings - 1) * segments).reshape(rings - 1, segments)
    j = np.roll(np.arange(segments), -1)
    faces = [np.stack([np.zeros(segments, int), idx[0], idx[0][j]], 1)]
    for r in range(rings - 2):
        a, b = idx[r], idx[r + 1]
        faces += [np.stack([a, b, b[j]], 1), np.stack([a, b[j], a[j]], 1)]
    last = len(v) - 1
    faces.append(np.stack([np.full(segments, last), idx[-1][j], idx[-1]], 1))
    return Mesh(v, np.concatenate(faces).astype(np.int32))


def disc(radius: float, height: float, segments: int = 128) -> Mesh:
    """A horizontal one-sided disc (a triangle fan) at y = height."""
    a = 2 * np.pi * np.arange(segments) / segments
    v = np.concatenate(
        [[[0.0, height, 0.0]], np.stack([radius * np.cos(a), np.full(segments, height), -radius * np.sin(a)], 1)]
    )
    i = 1 + np.arange(segments)
    return Mesh(v, np.stack([np.zeros(segments, int), i, 1 + i % segments], 1).astype(np.int32))


def torus(
    major: float, minor: float, centre=(0.0, 0.0, 0.0), upright: bool = True, segments: int = 64, sides: int = 24
) -> Mesh:
    """A torus (a shape with a hole); upright: its hole faces the z axis, else the y axis."""
    u = 2 * np.pi * np.arange(segments) / segments
    w = 2 * np.pi * np.arange(sides) / sides
    uu, ww = np.meshgrid(u, w, indexing="ij")
    r = major + minor * np.cos(ww)
    pts = np.stack([r * np.cos(uu), minor * np.sin(ww), -r * np.sin(uu)], -1).reshape(-1, 3)
    if upright:
        pts = pts[:, [0, 2, 1]] * [1, -1, 1]  # (x, -z, y): a proper rotation about x
    idx = np.arange(segments * sides).reshape(segments, sides)
    a, b = idx, np.roll(idx, -1, axis=0)
    c, d = np.roll(b, -1, axis=1), np.roll(a, -1, axis=1)
    f = np.concatenate([np.stack([a, b, c], -1).reshape(-1, 3), np.stack([a, c, d], -1).reshape(-1, 3)])
    return Mesh(pts + np.asarray(centre, float), f.astype(np.int32))


def merge(parts: list[Mesh]) -> Mesh:
    """Concatenate meshes (overlapping parts are fine: a shadow is a union)."""
    v, f, off = [], [], 0
    for p in parts:
        v.append(p.vertices)
        f.append(p.faces + off)
        off += len(p.vertices)
    return Mesh(np.concatenate(v), np.concatenate(f).astype(np.int32))


def rotate_y(mesh: Mesh, angle: float) -> Mesh:
    c, s = np.cos(angle), np.sin(angle)
    return Mesh(mesh.vertices @ np.array([[c, 0, s], [0, 1, 0], [-s, 0, c]]).T, mesh.faces)


def tilt(mesh: Mesh, angle: float) -> Mesh:
    """Rotate about the x axis (lean forward/back), then lift back onto y = 0."""
    c, s = np.cos(angle), np.sin(angle)
    v = mesh.vertices @ np.array([[1, 0, 0], [0, c, -s], [0, s, c]]).T
    return Mesh(v - [0.0, v[:, 1].min(), 0.0], mesh.faces)


def random_part(rng: np.random.Generator, y: float) -> Mesh:
    """A seeded box, cylinder or sphere standing at height ``y`` near the y axis."""
    kind = rng.integers(3)
    if kind == 0:
        size = rng.uniform(0.1, 0.6, 3)
        return box(size, (rng.uniform(-0.3, 0.3), y + size[1] / 2, rng.uniform(-0.3, 0.3)))
    if kind == 1:
        r, h = rng.uniform(0.05, 0.3), rng.uniform(0.1, 0.7)
        return cylinder(r, h, 32, (rng.uniform(-0.3, 0.3), y, rng.uniform(-0.3, 0.3)))
    r = rng.uniform(0.08, 0.3)
    return uv_sphere(r, (rng.uniform(-0.3, 0.3), y + r, rng.uniform(-0.3, 0.3)), 16, 32)


def generate(kind: str, seed: int) -> Mesh:
    """A seeded shape of one family."""
    rng = np.random.default_rng([seed, KINDS.index(kind)])
    if kind == "pole":  # thin poles, sometimes leaning, sometimes several, sometimes with a sign on top
        parts = []
        for _ in range(rng.integers(1, 4)):
            h = rng.uniform(0.6, 1.5)
            p = cylinder(rng.uniform(0.005, 0.03), h, 16, (rng.uniform(-0.3, 0.3), 0, rng.uniform(-0.3, 0.3)))
            parts.append(tilt(p, rng.uniform(-0.3, 0.3)) if rng.random() < 0.4 else p)
        if rng.random() < 0.4:  # a sign on the tallest pole's top
            tallest = max(parts, key=lambda p: p.vertices[:, 1].max())
            tip = tallest.vertices[tallest.vertices[:, 1] >= tallest.vertices[:, 1].max() - 1e-9].mean(axis=0)
            parts.append(box((rng.uniform(0.2, 0.6), rng.uniform(0.1, 0.3), 0.02), tip))
        return merge(parts)
    if kind == "slab":  # flat slabs: standing panels or lying plates, maybe on small feet
        w, h, t = rng.uniform(0.3, 1.0), rng.uniform(0.3, 1.0), rng.uniform(0.01, 0.05)
        if rng.random() < 0.5:
            return rotate_y(box((w, h, t), (0, h / 2, 0)), rng.uniform(0, np.pi))
        feet = rng.uniform(0.0, 0.3)
        parts = [box((w, t, h), (0, feet + t / 2, 0))]
        if feet > 0:
            parts += [cylinder(0.015, feet, 12, (sx * w * 0.4, 0, sz * h * 0.4)) for sx in (-1, 1) for sz in (-1, 1)]
        return merge(parts)
    if kind == "holes":  # rings and frames: shadows with holes
        if rng.random() < 0.5:
            major = rng.uniform(0.2, 0.5)
            minor = rng.uniform(0.02, 0.1)
            ring = torus(major, minor, (0, major + minor, 0), upright=rng.random() < 0.7)
            return rotate_y(ring, rng.uniform(0, np.pi))
        w, h, bar = rng.uniform(0.4, 1.0), rng.uniform(0.4, 1.0), rng.uniform(0.03, 0.1)
        d = rng.uniform(0.03, 0.3)
        frame = [
            box((w, bar, d), (0, bar / 2, 0)),
            box((w, bar, d), (0, h - bar / 2, 0)),
            box((bar, h, d), (-(w - bar) / 2, h / 2, 0)),
            box((bar, h, d), ((w - bar) / 2, h / 2, 0)),
        ]
        return rotate_y(merge(frame), rng.uniform(0, np.pi))
    if kind == "compound":  # stacked random primitives
        parts, y = [], 0.0
        for _ in range(rng.integers(2, 6)):
            p = random_part(rng, y)
            parts.append(p)
            y = p.vertices[:, 1].max() * rng.uniform(0.6, 1.0)
        return merge(parts)
    if kind == "arch":  # two legs and a lintel
        gap, h, t = rng.uniform(0.2, 0.8), rng.uniform(0.3, 1.0), rng.uniform(0.05, 0.2)
        return merge(
            [
                box((t, h, t), (-gap / 2 - t / 2, h / 2, 0)),
                box((t, h, t), (gap / 2 + t / 2, h / 2, 0)),
                box((gap + 2 * t, t, t), (0, h + t / 2, 0)),
            ]
        )
    if kind == "table":  # a top on legs: a shadow with light under it
        w, d, h = rng.uniform(0.4, 1.0), rng.uniform(0.3, 1.0), rng.uniform(0.2, 0.8)
        leg = rng.uniform(0.01, 0.05)
        legs = [cylinder(leg, h, 12, (sx * w * 0.45, 0, sz * d * 0.45)) for sx in (-1, 1) for sz in (-1, 1)]
        if rng.random() < 0.6:
            top = box((w, 0.03, d), (0, h + 0.015, 0))
        else:
            top = cylinder(max(w, d) / 2, 0.03, 48, (0, h, 0))
        return merge(legs + [top])
    raise ValueError(f"unknown procedural kind {kind!r}")


def procedural_items(count: int, seed: int) -> list[Item]:
    """``count`` items cycling through the families; split by item index (80/10/10)."""
    return [
        generated_item("procedural", "proc", "kind", KINDS[i % len(KINDS)], "object", seed, i) for i in range(count)
    ]


def build(params: dict) -> Mesh:
    return generate(params["kind"], params["seed"])
