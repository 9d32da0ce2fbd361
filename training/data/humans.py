"""Varied people from the ``anny`` body model (Apache-2.0 code, CC0 MakeHuman data; needs torch).

Each item's parameters are drawn from its seed with numpy alone and stored in
the item (phenotypes, pose family and every joint angle), so the set is
reproducible and inspectable without anny; :func:`build` poses the model.

Angles are in degrees, as ``anny``'s "local-ref" deltas (rotations about
world-aligned axes of the reference pose, anny's frame: x to the body's left,
-y forward, z up). Signs were measured on the model's joints: for the left
arm +y lowers the arm towards the body and -y raises it sideways, -x swings
it forward; for the legs -x swings the thigh forward and +x bends the knee.
Right-side y and z rotations are mirrored. Every angle is clipped to a
natural range (``LIMITS``).
"""

from __future__ import annotations

import math

import numpy as np

from .items import Item, item_seed, split_for
from .meshes import Mesh

POSES = ("standing", "walking", "arms_raised", "arms_crossed", "arm_out", "hands_on_hips")
# The ``anny_poses`` source's families: off the standing frame (their own source, so that the sets made of POSES
# stay as they were); a lying person is one of the others laid down (``LIE``)
MORE_POSES = ("running", "sitting", "crouching", "kneeling", "lying")
LIE = ("back", "front", "side")
PHENOTYPES = ("gender", "age", "muscle", "weight", "height", "proportions")
LIMITS = {  # (axis, lo, hi) per joint role, degrees, in the left side's convention
    "upperarm_y": (-160.0, 60.0),
    "upperarm_x": (-110.0, 50.0),
    "upperarm_z": (-60.0, 60.0),
    "elbow_x": (-140.0, 0.0),
    "elbow_z": (-110.0, 40.0),
    "hip_x": (-125.0, 30.0),
    "hip_y": (-25.0, 25.0),
    "knee_x": (0.0, 150.0),
    "spine_x": (-20.0, 20.0),
    "spine_z": (-25.0, 25.0),
    "head_z": (-45.0, 45.0),
    "head_x": (-25.0, 25.0),
}


STANDING = {  # (lo, hi) per joint role, each side: every pose starts from these
    "upperarm_y": (30, 50),
    "upperarm_x": (-15, 10),
    "elbow_x": (-25, 0),
    "hip_x": (-6, 4),
    "hip_y": (-6, 6),
    "knee_x": (0, 8),
}
# The arms of each pose but walking: (lo, hi) per joint role, over the standing ones; both arms, but arms_raised's
# are the left alone 2 times in 5 and arm_out's one, either
ARMS = {
    "arms_raised": {"upperarm_y": (-150, -70), "upperarm_x": (-30, 10), "elbow_x": (-60, 0)},
    "arms_crossed": {"upperarm_y": (35, 50), "upperarm_x": (-45, -25), "elbow_x": (-110, -80), "elbow_z": (-80, -50)},
    "arm_out": {"upperarm_y": (-50, -30), "upperarm_x": (-70, 0), "elbow_x": (-30, 0)},
    "hands_on_hips": {"upperarm_y": (0, 15), "upperarm_x": (5, 25), "elbow_x": (-100, -70), "elbow_z": (-60, -30)},
}


def _draw(a: dict[str, float], rng: np.random.Generator, sides: tuple[str, ...], ranges: dict) -> None:
    """Set joint role ``r`` of each of ``sides`` in ``a`` to a uniform draw from ``ranges[r]`` (lo, hi), side by
    side, in the order of ``ranges``."""
    for side in sides:
        for role, (lo, hi) in ranges.items():
            a[f"{role}_{side}"] = rng.uniform(lo, hi)


def _angles(pose: str, rng: np.random.Generator) -> dict[str, float]:
    """Joint angles (left-side convention for arms and legs, suffix _L/_R) of one pose family."""
    u = rng.uniform
    a: dict[str, float] = {}
    _draw(a, rng, ("L", "R"), STANDING)
    if pose == "walking":
        phase, stride = u(0, 2 * math.pi), u(15, 32)
        for side, sgn in (("L", 1.0), ("R", -1.0)):
            s = sgn * math.sin(phase)
            a[f"hip_x_{side}"] = -stride * s
            a[f"knee_x_{side}"] = max(0.0, 45 * sgn * math.sin(phase + 1.2)) + u(0, 8)
            a[f"upperarm_x_{side}"] = 0.8 * stride * s
            a[f"elbow_x_{side}"] = u(-35, -5)
    elif pose == "running":
        phase, stride = u(0, 2 * math.pi), u(30, 55)
        for side, sgn in (("L", 1.0), ("R", -1.0)):
            s = sgn * math.sin(phase)
            a[f"hip_x_{side}"] = -stride * s
            a[f"knee_x_{side}"] = 25 + 70 * max(0.0, sgn * math.sin(phase + 1.2)) + u(0, 15)
            a[f"upperarm_x_{side}"] = 1.1 * stride * s
            a[f"elbow_x_{side}"] = u(-110, -70)
    elif pose in ("sitting", "crouching"):  # on the ground: the thighs forward, the knees bent by as much
        hip, knee = ((-100, -75), (0, 100)) if pose == "sitting" else ((-125, -95), (115, 150))
        _draw(a, rng, ("L", "R"), {"hip_x": hip, "knee_x": knee, "upperarm_x": (-60, 10), "elbow_x": (-70, 0)})
    elif pose == "kneeling":  # on both knees, or on one with the other foot forward
        _draw(a, rng, ("L", "R"), {"hip_x": (-15, 5), "knee_x": (80, 100)})
        if rng.random() < 0.5:
            side = "L" if rng.random() < 0.5 else "R"
            a[f"hip_x_{side}"], a[f"knee_x_{side}"] = u(-100, -80), u(80, 100)
    elif pose == "lying":  # one of the others, laid down (build turns it)
        return _angles(str(rng.choice(POSES[:2] + ("arms_raised", "arm_out"))), rng)
    elif pose in ARMS:
        sides = ("L", "R")
        if pose == "arms_raised" and rng.random() >= 0.6:
            sides = ("L",)
        elif pose == "arm_out":
            sides = ("L",) if rng.random() < 0.5 else ("R",)
        _draw(a, rng, sides, ARMS[pose])
    a["spine_x"] = u(-8, 8)
    a["spine_z"] = u(-12, 12)
    a["head_z"] = u(-30, 30)
    a["head_x"] = u(-12, 12)
    out = {}
    for key, value in a.items():
        role = key[:-2] if key.endswith(("_L", "_R")) else key
        lo, hi = LIMITS[role]
        out[key] = float(np.clip(value, lo, hi))
    return out


def draw_params(seed: int, poses: tuple[str, ...] = POSES) -> dict:
    """Phenotypes (uniform in [0, 1], age in [0.25, 1]), pose family (one of ``poses``) and joint angles of one
    person; a lying one's side it lies on (``lie``, :data:`LIE`)."""
    rng = np.random.default_rng([seed, 7])
    pheno = {k: float(rng.uniform(0.25 if k == "age" else 0.0, 1.0)) for k in PHENOTYPES}
    pose = poses[int(rng.integers(len(poses)))]
    params = {"seed": int(seed), "phenotypes": pheno, "pose": pose, "angles": _angles(pose, rng)}
    return params | ({"lie": str(rng.choice(LIE))} if pose == "lying" else {})


def human_items(count: int, seed: int, poses: tuple[str, ...] = POSES) -> list[Item]:
    """``count`` anny people in ``poses`` (:data:`POSES`: the ``anny`` source; :data:`MORE_POSES`: ``anny_poses``);
    split by index (80/10/10)."""
    source, prefix = ("anny", "anny") if poses == POSES else ("anny_poses", "annyp")
    out = []
    for i in range(count):
        params = draw_params(item_seed(seed, i), poses) | {
            "licence": "CC0-1.0 (MakeHuman body data via anny, Apache-2.0 code)",
            "attribution": "anny (NAVER Corp.) / MakeHuman",
        }
        out.append(Item(f"{prefix}_{seed}_{i:04d}", split_for(i), "human", f"anny_{params['pose']}", source, params))
    return out


_MODEL = None


def _model():
    global _MODEL
    if _MODEL is None:  # anny (and torch under it) load only when a person is built: other sources need neither
        import anny
        import torch

        torch.set_num_threads(1)
        model = anny.Anny()
        _MODEL = (model, model.get_triangular_faces().numpy().astype(np.int32))
    return _MODEL


def _rotation(axes: list[tuple[str, float]]):
    import roma  # as anny: only when a person is built
    import torch

    r = torch.eye(3, dtype=torch.float64)
    for axis, deg in axes:
        v = torch.zeros(3, dtype=torch.float64)
        v["xyz".index(axis)] = math.radians(deg)
        r = r @ roma.rotvec_to_rotmat(v)
    t = torch.eye(4, dtype=torch.float64)
    t[:3, :3] = r
    return t[None]


def build(params: dict) -> Mesh:
    """Pose anny with the recorded parameters; returns the mesh in y-up world axes."""
    import torch  # as anny: only when a person is built

    model, faces = _model()
    a = params["angles"]
    pose = {}
    for side, m in (("L", 1.0), ("R", -1.0)):
        pose[f"upperarm01.{side}"] = _rotation([("y", m * a[f"upperarm_y_{side}"]), ("x", a[f"upperarm_x_{side}"])])
        pose[f"lowerarm01.{side}"] = _rotation([("x", a[f"elbow_x_{side}"]), ("z", m * a.get(f"elbow_z_{side}", 0.0))])
        pose[f"upperleg01.{side}"] = _rotation([("x", a[f"hip_x_{side}"]), ("y", m * a[f"hip_y_{side}"])])
        pose[f"lowerleg01.{side}"] = _rotation([("x", a[f"knee_x_{side}"])])
    pose["spine03"] = _rotation([("x", a["spine_x"]), ("z", a["spine_z"])])
    pose["head"] = _rotation([("z", a["head_z"]), ("x", a["head_x"])])
    with torch.no_grad():
        out = model(
            pose_parameters={k: v.to(model.dtype) for k, v in pose.items()}, phenotype_kwargs=params["phenotypes"]
        )
    v = out["vertices"][0].double().numpy()
    # anny: x left, -y forward, z up -> world: y up, the person facing +z (towards the yaw-0 camera).
    world = np.stack([v[:, 0], v[:, 2], -v[:, 1]], axis=1)
    lie = params.get("lie")
    if lie == "back":  # the face up: (x, y, z) -> (x, -z, y)
        world = np.stack([world[:, 0], -world[:, 2], world[:, 1]], axis=1)
    elif lie == "front":
        world = np.stack([world[:, 0], world[:, 2], -world[:, 1]], axis=1)
    elif lie == "side":  # on the left side: (x, y, z) -> (-y, x, z)
        world = np.stack([-world[:, 1], world[:, 0], world[:, 2]], axis=1)
    return Mesh(world, faces)
