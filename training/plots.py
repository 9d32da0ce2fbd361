"""PNG figures without matplotlib: loss curves and image grids (PIL only)."""

from __future__ import annotations

import csv
import math
import sys
from pathlib import Path

import numpy as np
from PIL import Image, ImageDraw

COLOURS = [
    (31, 119, 180),
    (255, 127, 14),
    (44, 160, 44),
    (214, 39, 40),
    (148, 103, 189),
    (140, 86, 75),
    (227, 119, 194),
    (127, 127, 127),
]


def loss_curve(
    series: dict[str, list[tuple[float, float]]],
    path: str | Path,
    title: str = "",
    xlabel: str = "step",
    size: tuple[int, int] = (720, 420),
) -> None:
    """Plot named (x, y) series on a log-y axis and save a PNG."""
    w, h = size
    left, right, top, bottom = 70, 20, 30, 45
    img = Image.new("RGB", size, "white")
    d = ImageDraw.Draw(img)
    pts = [(x, y) for s in series.values() for x, y in s if y > 0 and math.isfinite(y)]
    d.text((left, 8), title, fill="black")
    if not pts:
        img.save(path)
        return
    x0, x1 = min(p[0] for p in pts), max(p[0] for p in pts)
    ly0, ly1 = math.log10(min(p[1] for p in pts)), math.log10(max(p[1] for p in pts))
    if x1 == x0:
        x1 = x0 + 1
    if ly1 - ly0 < 1e-6:
        ly0, ly1 = ly0 - 0.5, ly1 + 0.5
    ly0, ly1 = math.floor(ly0 * 4) / 4, math.ceil(ly1 * 4) / 4

    def to_px(x: float, y: float) -> tuple[float, float]:
        px = left + (x - x0) / (x1 - x0) * (w - left - right)
        py = top + (ly1 - math.log10(y)) / (ly1 - ly0) * (h - top - bottom)
        return px, py

    d.rectangle([left, top, w - right, h - bottom], outline="black")
    for k in range(int(math.floor(ly0)), int(math.ceil(ly1)) + 1):
        for m in (1, 2, 5):
            val = m * 10.0**k
            if ly0 <= math.log10(val) <= ly1:
                _, py = to_px(x0, val)
                d.line([left, py, w - right, py], fill=(225, 225, 225))
                d.text((5, py - 6), f"{val:.0e}", fill="black")
    for i in range(6):
        x = x0 + (x1 - x0) * i / 5
        px, _ = to_px(x, 10**ly0)
        d.text((px - 15, h - bottom + 5), f"{x:.0f}", fill="black")
    d.text((w // 2 - 20, h - 18), xlabel, fill="black")
    for n, (name, s) in enumerate(series.items()):
        c = COLOURS[n % len(COLOURS)]
        xy = [to_px(x, y) for x, y in s if y > 0 and math.isfinite(y)]
        if len(xy) > 1:
            d.line(xy, fill=c, width=2)
        elif xy:
            d.ellipse([xy[0][0] - 2, xy[0][1] - 2, xy[0][0] + 2, xy[0][1] + 2], fill=c)
        d.text((w - right - 190, top + 8 + 14 * n), f"-- {name}", fill=c)
    img.save(path)


def image_grid(
    rows: list[list[np.ndarray]], path: str | Path, labels: list[str] | None = None, cell: int = 128, pad: int = 2
) -> None:
    """Save a grid of [0, 1] greyscale images (rows of equal length), optionally with column labels."""
    n_rows, n_cols = len(rows), max(len(r) for r in rows)
    label_h = 14 if labels else 0
    img = Image.new("L", (n_cols * (cell + pad) + pad, n_rows * (cell + pad) + pad + label_h), 255)
    d = ImageDraw.Draw(img)
    if labels:
        for j, text in enumerate(labels):
            d.text((pad + j * (cell + pad) + 2, 1), text, fill=0)
    for i, row in enumerate(rows):
        for j, a in enumerate(row):
            a = np.clip(np.asarray(a, np.float32), 0, 1)
            tile = Image.fromarray((a * 255 + 0.5).astype(np.uint8), "L")
            tile = tile.resize((cell, cell), Image.Resampling.BILINEAR)
            img.paste(tile, (pad + j * (cell + pad), label_h + pad + i * (cell + pad)))
    img.save(path, optimize=True)


def runs_figure(runs: list[str], path: str | Path, title: str = "training loss (per-pixel L2)") -> None:
    """One loss-curve PNG for several runs: train and validation loss of each against samples seen."""
    series: dict[str, list[tuple[float, float]]] = {}
    for run in runs:
        rows = list(csv.DictReader((Path(run) / "log.csv").open()))
        name = Path(run).name
        series[f"{name} train"] = [(float(r["samples"]), float(r["train_loss"])) for r in rows if r["train_loss"]]
        series[f"{name} val"] = [(float(r["samples"]), float(r["val_loss"])) for r in rows if r["val_loss"]]
    loss_curve(series, path, title, xlabel="samples", size=(900, 480))


if __name__ == "__main__":
    runs_figure(sys.argv[2:], sys.argv[1])
