"""A picture sheet of the canvas evaluation: per group, the truth and a prediction under each light size."""

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


def write_sheet(data: Path, predictions: Path, out: Path, names: list[str] | None = None, mode: str = "camera") -> None:
    """Rows: groups; columns: truth and prediction at each size of ``cases.ANGLES``. Writes a PNG to ``out``."""
    groups = {g.name: g for g in cases.read_groups(data)}
    names = names or default_groups(list(groups.values()))
    unknown = [n for n in names if n not in groups]
    if unknown:
        raise ValueError(f"unknown groups {unknown}; the set has {sorted(groups)}")
    first = groups[names[0]]
    height = round(PANEL_WIDTH * first.height / first.width)
    cols = 2 * len(cases.ANGLES)
    sheet = Image.new("L", (cols * PANEL_WIDTH, len(names) * (height + LABEL)), 255)
    draw = ImageDraw.Draw(sheet)
    for r, name in enumerate(names):
        group = groups[name]
        mask = cases.read_mask(data, group)
        for k, angle in enumerate(cases.ANGLES):
            truth = cases.read_truth(data, group, angle)
            pred = read_layer(prediction_path(predictions, mode, group, angle), truth.shape)
            for j, (what, s) in enumerate((("truth", truth), (mode, pred))):
                x, y = (2 * k + j) * PANEL_WIDTH, r * (height + LABEL)
                panel = Image.fromarray(composite(s, mask)).resize((PANEL_WIDTH, height), Image.Resampling.LANCZOS)
                sheet.paste(panel, (x, y + LABEL))
                draw.text((x + 4, y + 2), f"{group.name} {angle:g} deg: {what}", fill=0)
    out.parent.mkdir(parents=True, exist_ok=True)
    sheet.save(out, optimize=True)


__all__ = ["composite", "default_groups", "write_sheet"]
