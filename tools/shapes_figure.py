"""A sheet of generated shapes: the procedural animals, the people off their feet and the objects with flat parts
on the ground, from three sides.

    PYTHONPATH=. python tools/shapes_figure.py --out docs/img/new_shapes.png

Each tile is one view at R = 128 (the surface model's frame, pitch 15 degrees), cropped to the shape: its pixel
heights dark (0) to light (half a frame), the ground white. Needs anny for the people.
"""

from __future__ import annotations

import argparse
from pathlib import Path

import numpy as np
from PIL import Image

from training.data import meshes
from training.data.grounded import grounded_items
from training.data.humans import MORE_POSES, human_items
from training.data.quadrupeds import quadruped_items
from training.data.sources import build_mesh
from training.data.surface_views import view_record

from surface_reading_figure import crop_square, shade_heights  # the tools folder: the script's own

TILE = 160
YAWS = (90.0, 35.0, 0.0)


def _tile(view: dict) -> np.ndarray:
    mask, height = view["mask"] > 0.5, np.nan_to_num(view["height"])
    rgb = shade_heights(height, mask)[crop_square(mask)].astype(np.uint8)
    return np.asarray(Image.fromarray(rgb).resize((TILE, TILE), Image.Resampling.BILINEAR))


def sheet(animals: int, people: int, grounded: int) -> Image.Image:
    """Rows of validation shapes (``animals`` procedural animals, ``people`` anny people off their feet, then
    ``grounded`` objects with parts on the ground), each from :data:`YAWS`; two shapes a row."""
    items = [it for it in quadruped_items(200, 0) if it.split == "val"][:animals]
    items += [it for it in human_items(60, 0, MORE_POSES) if it.split == "val"][:people]
    items += [it for it in grounded_items(200, 0) if it.split == "val"][:grounded]
    tiles = []
    for item in items:
        mesh = build_mesh(item)
        topo = meshes.topology(mesh)
        tiles.append(np.concatenate([_tile(view_record(mesh, topo, yaw, 15.0, 45.0)) for yaw in YAWS], axis=1))
    if len(tiles) % 2:
        tiles.append(np.full_like(tiles[0], 255))
    rows = [
        np.concatenate([np.pad(t, ((2, 2), (2, 2), (0, 0)), constant_values=255) for t in tiles[i : i + 2]], 1)
        for i in range(0, len(tiles), 2)
    ]
    return Image.fromarray(np.concatenate(rows, axis=0))


def main() -> None:
    p = argparse.ArgumentParser(description=(__doc__ or "").split("\n")[0])
    p.add_argument("--animals", type=int, default=10)
    p.add_argument("--people", type=int, default=6)
    p.add_argument("--grounded", type=int, default=8)
    p.add_argument("--out", type=Path, required=True)
    args = p.parse_args()
    sheet(args.animals, args.people, args.grounded).save(args.out, optimize=True)


if __name__ == "__main__":
    main()
