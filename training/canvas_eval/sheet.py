"""A picture sheet of the canvas evaluation: per group, the truth and predictions under each light size."""

from __future__ import annotations

from pathlib import Path

import numpy as np
from PIL import Image, ImageDraw

from . import cases
from .score import prediction_path, read_layer

PANEL_WIDTH = 320
LABEL = 16  # pixels of caption above each panel
OBJECT_GREY = 0.55


def composite(s: np.ndarray, mask: np.ndarray) -> np.ndarray:
    """The shadow on white ground with the object in flat grey over it, (H, W) uint8."""
    ground = 1.0 - np.clip(s, 0.0, 1.0)
    return np.round(255 * (ground * (1 - mask) + OBJECT_GREY * mask)).astype(np.uint8)


def default_groups(groups: list[cases.Group], count: int = 4) -> list[str]:
    """``count`` group names spread over the set, one per shape where possible."""
    by_shape: dict[str, cases.Group] = {}
    for g in groups:
        by_shape.setdefault(g.shape, g)
    firsts = list(by_shape.values())
    return [firsts[i].name for i in np.linspace(0, len(firsts) - 1, count).round().astype(int)]


def panel_sheet(rows: list[list[tuple[str, np.ndarray, np.ndarray]]], out: Path) -> None:
    """A PNG at ``out`` of panels ``PANEL_WIDTH`` wide, a row of them per list: each (caption, s, the object's
    mask) drawn by :func:`composite` under its caption."""
    first = rows[0][0][1]
    height = round(PANEL_WIDTH * first.shape[0] / first.shape[1])
    sheet = Image.new("L", (max(map(len, rows)) * PANEL_WIDTH, len(rows) * (height + LABEL)), 255)
    draw = ImageDraw.Draw(sheet)
    for r, row in enumerate(rows):
        for c, (caption, s, mask) in enumerate(row):
            x, y = c * PANEL_WIDTH, r * (height + LABEL)
            panel = Image.fromarray(composite(s, mask)).resize((PANEL_WIDTH, height), Image.Resampling.LANCZOS)
            sheet.paste(panel, (x, y + LABEL))
            draw.text((x + 4, y + 2), caption, fill=0)
    out.parent.mkdir(parents=True, exist_ok=True)
    sheet.save(out, optimize=True)


def write_sheet(
    data: Path,
    predictions: list[Path],
    out: Path,
    names: list[str] | None = None,
    mode: str = "camera",
    angles: list[float] | None = None,
) -> None:
    """Rows: groups; columns: the truth and each folder's prediction (captioned by the folder's name) at each of
    the group's sizes (``angles``: those alone). Writes a PNG to ``out``."""
    groups = {g.name: g for g in cases.read_groups(data)}
    names = names or default_groups(list(groups.values()))
    unknown = [n for n in names if n not in groups]
    if unknown:
        raise ValueError(f"unknown groups {unknown}; the set has {sorted(groups)}")
    label = (lambda p: mode) if len(predictions) == 1 else (lambda p: f"{p.name} ({mode})")
    rows = []
    for name in names:
        group = groups[name]
        mask = cases.read_mask(data, group)
        row = []
        for angle in [a for a in group.angles if angles is None or any(abs(a - b) < 1e-6 for b in angles)]:
            truth = cases.read_truth(data, group, angle)
            row.append((f"{group.name} {angle:g} deg: truth", truth, mask))
            for folder in predictions:
                pred = read_layer(prediction_path(folder, mode, group, angle), truth.shape)
                row.append((f"{group.name} {angle:g} deg: {label(folder)}", pred, mask))
        rows.append(row)
    panel_sheet(rows, out)


__all__ = ["composite", "default_groups", "panel_sheet", "write_sheet"]
