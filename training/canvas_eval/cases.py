"""The canvas-scale test set: which shapes, cameras and disk lights, and how a rendered case is stored.

Each *group* is one held-out shape (the test split of the shared meshes' manifest) seen from one camera
under one light direction; it is rendered under each light size of ``ANGLES``, so the sizes differ in
nothing else. On disk (``data/canvas_test/`` by default, git-ignored)::

    cases.json                  the groups: shape, kind, category, yaw, pitch, light, canvas camera
    GROUP/cutout.png            the object's silhouette as alpha (RGB a flat grey), canvas size
    GROUP/light_ANGLE.json      the light-map file: the disk's ``angle`` and its equivalent ``softness``
    GROUP/truth_ANGLE.npz       s over the canvas, uint16 (s * 65535), key ``s``
"""

from __future__ import annotations

import json
import os
from dataclasses import asdict, dataclass, replace
from pathlib import Path

import numpy as np
from PIL import Image

from training.data.items import Item, stable_hash
from training.data.views import PITCHES, YAWS

from .disk import HAZY, SOFTBOX, SUN, light_map_file

ANGLES = (SUN, HAZY, SOFTBOX)
FLOATING_ANGLES = (SUN, HAZY)  # a floating set's sizes: the lights whose shadow detaches crisply
LIFTS = (0.15, 0.8)  # a floating set's shapes float this share of their height above the ground, drawn uniformly
SHADOW_ON_CANVAS = 0.5  # a floating case's light casts at least this share of its shape's vertices onto the canvas
KIND_QUOTA = {"object": 7, "animal": 3, "human": 2}  # shapes per kind, 12 in all
ELEVATIONS = (10.0, 70.0)  # light elevations are drawn uniformly in this range (degrees)
CUTOUT_GREY = 128
S_SCALE = 65535


@dataclass(frozen=True)
class Group:
    """One shape, camera and light direction; rendered under every size of ``ANGLES``."""

    name: str
    shape: str
    kind: str
    category: str
    yaw: float
    pitch: float
    elevation: float
    azimuth: float
    width: int
    height: int
    seed: int = 0  # with the name and the size, seeds the jitter of the disk's directions
    horizon: float = float("nan")  # the canvas camera, filled in by the render
    fov: float = float("nan")
    lift_share: float = 0.0  # a floating case: the shape floats this share of its height above the ground
    lift: float = 0.0  # and its lift in canvas rows (conventions, "Lift and thickness"), filled in by the render

    @property
    def angles(self) -> tuple[float, ...]:
        """The light sizes this group is rendered under."""
        return FLOATING_ANGLES if self.lift_share > 0 else ANGLES

    def light_file(self, angle: float) -> dict:
        """The light-map file of this group's light at size ``angle``."""
        return light_map_file(self.elevation, self.azimuth, angle)


def pick_shapes(items: list[Item], quota: dict[str, int] | None = KIND_QUOTA, split: str = "test") -> list[Item]:
    """``split`` items (the test set's; "val": a set to choose models by), in stable-hash order, up to ``quota``
    per kind: distinct categories first, then any to fill the quota (None: every item of the split)."""
    ordered = sorted((it for it in items if it.split == split), key=lambda it: (stable_hash(it.id), it.id))
    if quota is None:
        return sorted(ordered, key=lambda it: (it.kind, it.id))
    picked: list[Item] = []
    for distinct in (True, False):
        for it in ordered:
            same_kind = [p for p in picked if p.kind == it.kind]
            if it in picked or len(same_kind) >= quota.get(it.kind, 0):
                continue
            if distinct and any(p.category == it.category for p in same_kind):
                continue
            picked.append(it)
    return sorted(picked, key=lambda it: (it.kind, it.id))


def make_groups(
    items: list[Item], lights: int, width: int, height: int, seed: int = 0, floating: bool = False
) -> list[Group]:
    """``lights`` groups per shape: yaw from the paper's views, pitch cycling over 0, 15 and 30 degrees
    across all groups, light elevation uniform in ``ELEVATIONS`` and azimuth uniform all round; ``floating``:
    each shape lifted by a share of its height drawn uniformly in ``LIFTS``."""
    groups = []
    for i, it in enumerate(items):
        for k in range(lights):
            rng = np.random.default_rng([seed, stable_hash(it.id), k])
            lift_share = round(float(np.random.default_rng([seed, stable_hash(it.id), k, 1]).uniform(*LIFTS)), 3)
            groups.append(
                Group(
                    name=f"{it.id}_{k}",
                    shape=it.id,
                    kind=it.kind,
                    category=it.category,
                    yaw=float(rng.choice(YAWS)),
                    pitch=float(PITCHES[(i * lights + k) % len(PITCHES)]),
                    elevation=round(float(rng.uniform(*ELEVATIONS)), 2),
                    azimuth=round(float(rng.uniform(-180.0, 180.0)), 2),
                    width=width,
                    height=height,
                    seed=seed,
                    lift_share=lift_share if floating else 0.0,
                )
            )
    return groups


def relit(group: Group, attempt: int) -> Group:
    """``group`` under its ``attempt``-th other light direction (attempt >= 1), drawn as :func:`make_groups` draws
    one: for a floating case whose shadow that light casts off the canvas, where no prediction can be scored."""
    rng = np.random.default_rng([group.seed, stable_hash(group.name), attempt, 2])
    return replace(
        group,
        elevation=round(float(rng.uniform(*ELEVATIONS)), 2),
        azimuth=round(float(rng.uniform(-180.0, 180.0)), 2),
    )


def angle_tag(angle: float) -> str:
    return f"{angle:g}"


def write_groups(root: Path, groups: list[Group]) -> None:
    root.mkdir(parents=True, exist_ok=True)
    _atomic_write(root / "cases.json", json.dumps([asdict(g) for g in groups], indent=1).encode())


def read_groups(root: Path) -> list[Group]:
    """The groups of a rendered test set (``cases.json``)."""
    path = Path(root) / "cases.json"
    if not path.is_file():
        raise FileNotFoundError(
            f"{path}: no canvas test set here (render one with 'python -m training.canvas_eval render')"
        )
    return [Group(**g) for g in json.loads(path.read_text())]


def _atomic_write(path: Path, data: bytes) -> None:
    tmp = path.with_name(path.name + ".part")
    tmp.write_bytes(data)
    os.replace(tmp, path)


def cutout_path(root: Path, group: Group) -> Path:
    return Path(root) / group.name / "cutout.png"


def light_path(root: Path, group: Group, angle: float) -> Path:
    return Path(root) / group.name / f"light_{angle_tag(angle)}.json"


def truth_path(root: Path, group: Group, angle: float) -> Path:
    return Path(root) / group.name / f"truth_{angle_tag(angle)}.npz"


def write_cutout(root: Path, group: Group, mask: np.ndarray) -> None:
    """The cutout: RGB a flat grey, alpha the mask's coverage."""
    path = cutout_path(root, group)
    path.parent.mkdir(parents=True, exist_ok=True)
    rgba = np.empty((*mask.shape, 4), np.uint8)
    rgba[..., :3] = CUTOUT_GREY
    rgba[..., 3] = np.round(np.clip(mask, 0.0, 1.0) * 255).astype(np.uint8)
    tmp = path.with_name("cutout.part.png")
    Image.fromarray(rgba, "RGBA").save(tmp)
    os.replace(tmp, path)


def read_mask(root: Path, group: Group) -> np.ndarray:
    """The cutout's alpha / 255, (H, W) float32."""
    with Image.open(cutout_path(root, group)) as im:
        return np.asarray(im.convert("RGBA"))[..., 3].astype(np.float32) / 255.0


def write_truth(root: Path, group: Group, angle: float, s: np.ndarray) -> None:
    path = truth_path(root, group, angle)
    path.parent.mkdir(parents=True, exist_ok=True)
    _atomic_write(light_path(root, group, angle), json.dumps(group.light_file(angle), indent=1).encode())
    tmp = path.with_name(path.stem + ".part.npz")
    np.savez_compressed(tmp, s=np.round(np.clip(s, 0.0, 1.0) * S_SCALE).astype(np.uint16))
    os.replace(tmp, path)


def read_truth(root: Path, group: Group, angle: float) -> np.ndarray:
    """The true s of a group at size ``angle``, (H, W) float32 in [0, 1]."""
    with np.load(truth_path(root, group, angle)) as z:
        return z["s"].astype(np.float32) / S_SCALE


__all__ = [
    "ANGLES",
    "FLOATING_ANGLES",
    "LIFTS",
    "SHADOW_ON_CANVAS",
    "Group",
    "angle_tag",
    "cutout_path",
    "light_path",
    "make_groups",
    "pick_shapes",
    "read_groups",
    "read_mask",
    "read_truth",
    "relit",
    "truth_path",
    "write_cutout",
    "write_groups",
    "write_truth",
]
