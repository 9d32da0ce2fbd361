"""A sheet of the surface model's reading against the truth: per row one view of a ``training.surface make`` set,
the true pixel heights, then each graph's reading and its error map with its mean (rows of R = 128).

    PYTHONPATH=. python tools/surface_reading_figure.py --sets data/surface_q/val_q.npz data/surface_q/oos.npz \
        --graphs ssn_engine/models/surface.onnx DIR/surface.onnx --names shipped fine-tuned \
        --rows 4 --out docs/img/surface_reading.png

Pixel heights are drawn dark (0) to light (half a frame and more) on the object, the ground white; an error map
white (0) to red (8 rows and more).
"""

from __future__ import annotations

import argparse
from pathlib import Path

import numpy as np
import onnxruntime as ort
from PIL import Image, ImageDraw

from training.data.surface_views import R, load

TILE = 192  # each tile: the view's object, cropped square with a margin, drawn this many pixels wide
ERROR_FULL = 8.0  # rows of R: an error map's full red


def crop_square(mask: np.ndarray) -> tuple[slice, slice]:
    """A square around the object's pixels with a tenth of its size as margin, inside the frame."""
    ys, xs = np.nonzero(mask > 0)
    size = int(max(np.ptp(ys), np.ptp(xs)) * 1.2) + 4
    cy, cx = (ys.min() + ys.max()) // 2, (xs.min() + xs.max()) // 2
    top = int(np.clip(cy - size // 2, 0, max(R - size, 0)))
    left = int(np.clip(cx - size // 2, 0, max(R - size, 0)))
    return slice(top, top + size), slice(left, left + size)


def _tile(rgb: np.ndarray, crop: tuple[slice, slice], label: str) -> Image.Image:
    tile = Image.fromarray(rgb[crop].astype(np.uint8)).resize((TILE, TILE), Image.Resampling.NEAREST)
    ImageDraw.Draw(tile).text((4, 4), label, fill=(200, 0, 0))
    return tile


def shade_heights(height: np.ndarray, mask: np.ndarray) -> np.ndarray:
    """Pixel heights (rows of R) as RGB: dark (0) to light (half a frame and more) where ``mask``, white elsewhere."""
    shade = np.clip(height / (R / 2), 0.0, 1.0) * 200.0 + 30.0
    return np.repeat(np.where(mask > 0, shade, 255.0)[..., None], 3, axis=-1)


def _errors(error: np.ndarray, mask: np.ndarray) -> np.ndarray:
    e = np.clip(error / ERROR_FULL, 0.0, 1.0) * (mask > 0)
    base = 225.0  # the object, where the reading is right: light grey
    rgb = np.stack([base + (255.0 - base) * e, base * (1.0 - e), base * (1.0 - e)], axis=-1)
    return np.where(mask[..., None] > 0, rgb, 255.0)


def sheet(sets: list[Path], graphs: list[Path], names: list[str], rows: int, seed: int = 0) -> Image.Image:
    """``rows`` views of each set (drawn with ``seed``), truth then each graph's reading."""
    sessions = [ort.InferenceSession(str(g), providers=["CPUExecutionProvider"]) for g in graphs]
    tiles: list[list[Image.Image]] = []
    rng = np.random.default_rng(seed)
    for path in sets:
        views = load([path])
        for i in rng.choice(len(views["mask"]), rows, replace=False):
            mask, truth = views["mask"][i].astype(np.float32), views["height"][i].astype(np.float32)
            crop = crop_square(mask)
            feed = {"mask": mask[None, None], "camera": views["camera"][i][None].astype(np.float32)}
            row = [_tile(shade_heights(truth, mask), crop, f"{path.stem} #{i}, pitch {views['pitch'][i]:.0f}: truth")]
            for name, sess in zip(names, sessions, strict=True):
                read = np.asarray(sess.run(None, feed)[0])[0, 0] * R
                error = np.abs(read - truth)
                row.append(_tile(shade_heights(read, mask), crop, f"{name}"))
                row.append(_tile(_errors(error, mask), crop, f"error {error[mask > 0].mean():.2f} rows"))
            tiles.append(row)
    w, h = tiles[0][0].size
    out = Image.new("RGB", (w * len(tiles[0]), h * len(tiles)), "white")
    for r, row in enumerate(tiles):
        for c, tile in enumerate(row):
            out.paste(tile, (c * w, r * h))
    return out


def main() -> None:
    p = argparse.ArgumentParser(description=(__doc__ or "").split("\n")[0])
    p.add_argument("--sets", nargs="+", type=Path, required=True)
    p.add_argument("--graphs", nargs="+", type=Path, required=True)
    p.add_argument("--names", nargs="+", required=True)
    p.add_argument("--rows", type=int, default=3, help="views per set")
    p.add_argument("--out", type=Path, required=True)
    args = p.parse_args()
    sheet(args.sets, args.graphs, args.names, args.rows).save(args.out, optimize=True)


if __name__ == "__main__":
    main()
