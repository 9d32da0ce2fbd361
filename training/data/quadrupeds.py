"""Procedural four-legged animals in several poses: shapes the shared meshes hold few of (31 training animals).

Each animal is a union of ellipsoids along segments: a body from rump to withers, a neck and a head, four legs of
two segments (thigh and shin), a tail and ears. Its proportions are drawn per item (a dachshund's short legs to a
horse's long ones, a short neck to a long one, a slim or a heavy body) and so is its pose (:data:`POSES`):
standing, walking (diagonal pairs in stride, a hoof lifted), grazing (the head down at the ground), lying (the
body on the ground, the legs folded) and sitting (the rump down, the forelegs straight). Like the other generated
shapes each item records its seed, so :func:`build` rebuilds the same mesh. World units, y up, the animal facing
+x (its yaw is drawn per view).
"""

from __future__ import annotations

import numpy as np

from .items import Item, generated_item
from .meshes import Mesh
from .procedural import merge, uv_sphere

POSES = ("standing", "walking", "grazing", "lying", "sitting")


def ellipsoid(start, end, radius: float, depth: float | None = None) -> Mesh:
    """A closed ellipsoid whose long axis runs from ``start`` to ``end``, ``radius`` across it (``depth`` along
    the horizontal normal to the axis, default ``radius``)."""
    a, b = np.asarray(start, float), np.asarray(end, float)
    axis = b - a
    length = float(np.linalg.norm(axis))
    d = axis / length if length > 1e-9 else np.array([0.0, 1.0, 0.0])
    side = np.cross(d, [0.0, 1.0, 0.0])
    side = side / np.linalg.norm(side) if np.linalg.norm(side) > 1e-6 else np.array([0.0, 0.0, 1.0])
    up = np.cross(d, side)  # (up, d, side) right-handed, so the sphere's outward faces stay outward
    unit = uv_sphere(1.0, rings=10, segments=20)  # y: along the axis
    half = max(length / 2, radius)
    frame = np.stack([up * radius, d * half, side * (radius if depth is None else depth)])
    return Mesh(unit.vertices @ frame + (a + b) / 2, unit.faces)


def _leg(hip: np.ndarray, foot: np.ndarray, length: float, radius: float, knee_forward: float) -> list[Mesh]:
    """A leg from ``hip`` to ``foot`` in two segments of ``length`` / 2, bent at a knee that points along x by the
    sign of ``knee_forward`` (a folded leg's knee juts out, a straight one's stays on the line)."""
    span = float(np.linalg.norm(foot - hip))
    bend = np.sqrt(max((length / 2) ** 2 - (span / 2) ** 2, 0.0))
    knee = (hip + foot) / 2 + np.array([np.sign(knee_forward) * bend, 0.0, 0.0])
    return [ellipsoid(hip, knee, radius * 1.3), ellipsoid(knee, foot, radius)]


def generate(pose: str, seed: int) -> Mesh:
    """A seeded animal in ``pose`` (:data:`POSES`), its lowest point at y = 0 (before normalising)."""
    rng = np.random.default_rng([seed, POSES.index(pose), 11])
    u = rng.uniform
    body, girth = u(0.7, 1.3), u(0.12, 0.26)  # rump to withers; the body's half height
    width = girth * u(0.7, 1.1)
    legs, leg_r = u(0.3, 1.1), u(0.025, 0.07)  # a leg's length (thigh + shin)
    neck, neck_r = u(0.15, 0.6), girth * u(0.35, 0.6)
    head, head_r = u(0.15, 0.35), u(0.05, 0.11)
    tail = u(0.0, 0.6)
    splay = width * 0.6  # the legs' offset from the body's middle
    rump_y = withers_y = legs
    body_pitch = 0.0
    if pose == "lying":
        rump_y = withers_y = girth * u(0.9, 1.1)
    elif pose == "sitting":
        rump_y = girth * u(0.9, 1.2)
        withers_y = max(legs, rump_y + 0.2 * body)
    rump = np.array([-body / 2, rump_y, 0.0])
    withers = np.array([body / 2, withers_y, 0.0])
    if pose == "sitting":  # keep the body's length: the withers rise over a shorter run
        rise = withers_y - rump_y
        withers[0] = rump[0] + np.sqrt(max(body**2 - rise**2, (0.3 * body) ** 2))
        body_pitch = np.arctan2(rise, withers[0] - rump[0])
    parts = [ellipsoid(rump, withers, girth, width)]
    # the neck and head: up and forward, or down to the ground when grazing
    lift = np.radians(u(-60.0, -35.0) if pose == "grazing" else u(15.0, 70.0))
    turn = np.radians(u(-40.0, 40.0))
    direction = np.array([np.cos(lift) * np.cos(turn), np.sin(lift), np.cos(lift) * np.sin(turn)])
    base = withers + np.array([0.0, girth * 0.5, 0.0])
    nod = np.radians(u(-70.0, -10.0))
    if pose == "grazing":  # the neck long enough for the muzzle, pointing down, to reach the grass
        nod = np.radians(u(-90.0, -60.0))
        neck = max(neck, (base[1] - head * 0.8 - head_r) / -np.sin(lift))
    top = base + neck * direction
    parts.append(ellipsoid(base, top, neck_r))
    muzzle = top + head * np.array([np.cos(nod) * np.cos(turn), np.sin(nod), np.cos(nod) * np.sin(turn)])
    parts.append(ellipsoid(top, muzzle, head_r))
    for z in (-1.0, 1.0):  # ears
        ear = top + np.array([0.0, head_r * 0.8, z * head_r * 0.6])
        parts.append(ellipsoid(ear, ear + [u(-0.02, 0.02), u(0.03, 0.12), z * u(0.0, 0.04)], head_r * 0.3))
    if tail > 0.05:
        droop = np.radians(u(-80.0, 10.0))
        end = rump + tail * np.array([-np.cos(droop), np.sin(droop), 0.0])
        end[1] = max(end[1], leg_r)
        parts.append(ellipsoid(rump, end, leg_r * 0.8))
    # the legs: hips under the rump and the withers, feet on the ground (or folded beside the body)
    phase = u(0.0, 2 * np.pi)
    for front, joint in ((False, rump), (True, withers)):
        inset = np.array([(-1 if front else 1) * 0.08 * body * np.cos(body_pitch), -girth * 0.4, 0.0])
        for z in (-1.0, 1.0):
            hip = joint + inset + [0.0, 0.0, z * splay]
            if pose == "lying":  # legs folded along the ground, forelegs forward, hind legs under the belly
                reach = legs * u(0.3, 0.6)
                foot = hip + [reach if front else reach * 0.5, 0.0, z * u(0.0, 0.1)]
                foot[1] = leg_r
            elif pose == "sitting" and not front:  # haunches down, the hind feet forward on the ground
                foot = hip + [legs * u(0.3, 0.5), 0.0, z * u(0.0, 0.05)]
                foot[1] = leg_r
            else:
                stride = 0.0
                if pose == "walking":  # diagonal pairs move together
                    sign = z * (1.0 if front else -1.0)
                    stride = 0.35 * legs * np.sin(phase + (0.0 if sign > 0 else np.pi))
                elif pose == "grazing" and front:
                    stride = u(-0.15, 0.15) * legs
                foot = hip + [stride, 0.0, 0.0]
                foot[1] = 0.0
                if pose == "walking" and stride * (1 if front else -1) < -0.2 * legs:  # the leg swinging through
                    foot[1] = u(0.05, 0.2) * legs
            parts += _leg(hip, foot, legs * 1.05, leg_r, -1.0 if front else 1.0)
    mesh = merge(parts)
    return Mesh(mesh.vertices - [0.0, mesh.vertices[:, 1].min(), 0.0], mesh.faces)


def quadruped_items(count: int, seed: int) -> list[Item]:
    """``count`` animals cycling through the poses; split by item index (80/10/10), every split holding every
    pose (the pose's cycle steps on by one every ten items)."""
    return [
        generated_item("quadruped", "quad", "pose", POSES[(i + i // 10) % len(POSES)], "animal", seed, i)
        for i in range(count)
    ]


def build(params: dict) -> Mesh:
    return generate(params["pose"], params["seed"])
