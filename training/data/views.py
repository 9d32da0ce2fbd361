"""The views rendered of each item: the paper's grid of cameras, or cameras drawn from continuous ranges."""

from __future__ import annotations

import argparse

import numpy as np

YAWS = (0.0, 45.0, -45.0, 90.0, -90.0)
PITCHES = (0.0, 15.0, 30.0)
FOV_RANGE = (35.0, 55.0)
PITCH_RANGE = (0.0, 30.0)
YAW_RANGE = (-180.0, 180.0)
VIEWS = 15  # per item, either way
CAMERAS = ("paper", "continuous")
CAMERA_TEXT = {  # the dataset card's and the CLI's words for each kind of cameras
    "paper": "yaw 0, +-45, +-90 x pitch 0, 15, 30",
    "continuous": f"yaw uniform in [{YAW_RANGE[0]:g}, {YAW_RANGE[1]:g}), "
    f"pitch uniform in [{PITCH_RANGE[0]:g}, {PITCH_RANGE[1]:g}]",
}


def view_specs() -> list[tuple[float, float]]:
    """The paper's 15 views: (yaw, pitch) for yaw in 0, 45, -45, 90, -90 and pitch in 0, 15, 30."""
    return [(yaw, pitch) for yaw in YAWS for pitch in PITCHES]


def draw_view(k: int, rng: np.random.Generator, cameras: str = "paper") -> tuple[float, float, float]:
    """View k's (yaw, pitch, field of view), degrees. ``paper``: the paper's grid of :func:`view_specs`;
    ``continuous``: yaw uniform in ``YAW_RANGE``, pitch uniform in ``PITCH_RANGE``. The field of view is uniform in
    ``FOV_RANGE`` and drawn first, so a paper view's stream (and its texel jitter) is what it always was."""
    fov = float(rng.uniform(*FOV_RANGE))
    if cameras == "paper":
        yaw, pitch = view_specs()[k]
    elif cameras == "continuous":
        yaw, pitch = float(rng.uniform(*YAW_RANGE)), float(rng.uniform(*PITCH_RANGE))
    else:
        raise ValueError(f"cameras must be one of {CAMERAS}, got {cameras!r}")
    return yaw, pitch, fov


def pitch_groups(pitches: list[float]) -> dict[str, list[int]]:
    """The indices of ``pitches`` per table group, groups in pitch order: the pitch itself where every view has one
    of the paper's ``PITCHES``, else its third of ``PITCH_RANGE`` ("0-10", "10-20", "20-30")."""
    if all(p in PITCHES for p in pitches):
        labels = [f"{p:g}" for p in pitches]
    else:
        lo, hi = PITCH_RANGE
        step = (hi - lo) / 3
        bins = [min(2, int((p - lo) // step)) for p in pitches]
        labels = [f"{lo + b * step:g}-{lo + (b + 1) * step:g}" for b in bins]
    groups: dict[str, list[int]] = {}
    for i, label in sorted(enumerate(labels), key=lambda il: (float(il[1].split("-")[0]), il[0])):
        groups.setdefault(label, []).append(i)
    return groups


def add_split_arguments(parser: argparse.ArgumentParser) -> None:
    """The arguments of a command that writes a split's views to one file: --split, --cameras, --out, --seed."""
    parser.add_argument(
        "--split",
        required=True,
        choices=("train", "val", "test", "outsource"),
        help="outsource: the out-of-source meshes (SSN_MESHES=data/outsource_meshes, docs/canvas_eval.md)",
    )
    parser.add_argument("--cameras", nargs="+", default=["continuous"], choices=CAMERAS)
    parser.add_argument("--out", required=True)
    parser.add_argument("--seed", type=int, default=0, help="the items' seed (procedural shapes and people)")
