"""A layer's alpha split into the objects an artist sees in it, each to cast its own shadow.

Artists keep several objects on one layer (two horses, a person and a dog). Framed as one cutout they share one
frame, one camera reading and one contact line, and each casts a shadow far from the one it casts alone. The
rule (docs/engine.md, "Several objects on one layer"):

1. The parts are the connected pieces of the visible alpha (above the framing's ``ALPHA_THRESHOLD``, 8-connected),
   found on a grid of at most ``GRID`` cells along the layer's longer side: gaps narrower than a cell (an
   antialiased seam between an arm and a body) join their pieces.
2. A part is *large* when its area is at least ``MIN_AREA_SHARE`` of the largest part's and its height at least
   ``MIN_HEIGHT_SHARE`` of the largest part's height. Large parts, from the largest down, become objects, except
   that a large part joins an object already found when most of its bounding box (``INSIDE_SHARE``) lies inside
   that object's (a piece held in front of a body). Parts whose columns merely overlap stay apart: two horses side
   by side on one ground overlap in columns (a head over the other's back) without being one thing.
3. Every other part joins the object nearest to it (pixel distance) when it lies within ``REACH_SHARE`` of that
   object's height: a person's detached hand stays with the person. A part farther away is an object of its own
   (a ball across the floor), unless it is a speck (its longer side under ``SPECK_SHARE`` of the largest part's
   height, or under the framing's ``MIN_CUTOUT`` pixels), whose shadow would not show: it is left out. A speck is
   never an object; an alpha of specks only is one object, framed whole as a single session frames it.
4. At most ``MAX_OBJECTS`` objects: the smallest beyond them join their nearest object.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import cast

import numpy as np
from scipy import ndimage

from .framing import MIN_CUTOUT, alpha_bbox, alpha_threshold

GRID = 512  # cells along the layer's longer side on which the parts are found
MIN_AREA_SHARE = 0.04  # of the largest part's area: at or above, a part may be an object of its own
MIN_HEIGHT_SHARE = 0.2  # of the largest part's height: likewise
INSIDE_SHARE = 0.5  # of a large part's bounding box inside an object's: it is part of that object
REACH_SHARE = 0.2  # of an object's height: a small part this close to it belongs to it
SPECK_SHARE = 0.02  # of the largest part's height: a farther part whose longer side is below it casts nothing
MAX_OBJECTS = 8  # objects per layer (each costs a shadow inference per light change)


@dataclass(frozen=True)
class LayerObject:
    """One object of a layer: its bounding box on the canvas (x0, y0, x1, y1; x1, y1 exclusive) and its area in
    grid cells (for ordering only)."""

    bbox: tuple[int, int, int, int]
    area: int


@dataclass(frozen=True)
class LayerObjects:
    """A layer split into objects: ``objects`` largest first, and the object index of each grid cell
    (``cells`` (h, w) int, -1 for none) of ``cell`` canvas pixels a side, whose top-left corner lies at canvas
    point ``origin`` (x, y); ``left_out``: whether specks were left out of every object."""

    objects: tuple[LayerObject, ...]
    cells: np.ndarray
    cell: int
    origin: tuple[int, int]
    left_out: bool = False

    def alpha_of(self, index: int, alpha: np.ndarray) -> np.ndarray:
        """The canvas alpha of object ``index`` alone: ``alpha`` where its cells lie, 0 elsewhere."""
        x0, y0, x1, y1 = self.objects[index].bbox  # its top-left corner is a cell's
        ox, oy, c = *self.origin, self.cell
        own = self.cells[(y0 - oy) // c : -(-(y1 - oy) // c), (x0 - ox) // c : -(-(x1 - ox) // c)] == index
        cells = np.repeat(np.repeat(own, c, axis=0), c, axis=1)[: y1 - y0, : x1 - x0]
        out = np.zeros_like(alpha)
        out[y0:y1, x0:x1] = np.where(cells, alpha[y0:y1, x0:x1], 0)
        return out


@dataclass
class _Group:
    """Parts gathered as one object, on the grid: their labels and bounding box (rows, columns; end exclusive)."""

    labels: list[int]
    r0: int
    c0: int
    r1: int
    c1: int
    area: int

    @property
    def height(self) -> int:
        return self.r1 - self.r0

    def take(self, label: int, box: tuple[slice, slice], area: int) -> None:
        self.labels.append(label)
        self.r0, self.r1 = min(self.r0, box[0].start), max(self.r1, box[0].stop)
        self.c0, self.c1 = min(self.c0, box[1].start), max(self.c1, box[1].stop)
        self.area += area


def _cells(alpha: np.ndarray, bbox: tuple[int, int, int, int]) -> tuple[np.ndarray, int]:
    """The visible alpha in the box on a grid of at most ``GRID`` cells a side (a cell is visible where any of its
    pixels is), and the cell's side in canvas pixels."""
    x0, y0, x1, y1 = bbox
    cell = max(1, math.ceil(max(x1 - x0, y1 - y0) / GRID))
    rows, cols = math.ceil((y1 - y0) / cell), math.ceil((x1 - x0) / cell)
    visible = np.zeros((rows * cell, cols * cell), bool)
    visible[: y1 - y0, : x1 - x0] = alpha[y0:y1, x0:x1] > alpha_threshold(alpha.dtype)
    return np.asarray(visible.reshape(rows, cell, cols, cell).any(axis=(1, 3))), cell


def _inside(group: _Group, box: tuple[slice, slice]) -> bool:
    """Whether most of grid box ``box`` (``INSIDE_SHARE``) lies inside ``group``'s box."""
    r0, r1, c0, c1 = box[0].start, box[0].stop, box[1].start, box[1].stop
    inside = max(0, min(r1, group.r1) - max(r0, group.r0)) * max(0, min(c1, group.c1) - max(c0, group.c0))
    return inside >= INSIDE_SHARE * (r1 - r0) * (c1 - c0)


def split_objects(alpha: np.ndarray) -> LayerObjects:
    """Split a canvas alpha (H, W) of uint8, uint16 or float into objects (the module's rule).

    Parameters
    ----------
    alpha : np.ndarray
        The layer's alpha, as :func:`ssn_engine.framing.frame_alpha` takes it.

    Returns
    -------
    LayerObjects
        At least one object; :class:`ssn_engine.framing.EmptyAlphaError` where the alpha casts nothing.
    """
    bbox = alpha_bbox(alpha)
    visible, cell = _cells(alpha, bbox)
    labels, count = cast(tuple[np.ndarray, int], ndimage.label(visible, structure=np.ones((3, 3), bool)))
    boxes = ndimage.find_objects(labels)
    areas = np.bincount(labels.ravel(), minlength=count + 1)[1:]
    heights = np.array([b[0].stop - b[0].start for b in boxes])
    largest = int(np.argmax(areas))
    sides = np.array([max(b[0].stop - b[0].start, b[1].stop - b[1].start) for b in boxes])
    # A cell of c pixels may hold one visible pixel: n cells span at least (n - 2) c + 2 pixels.
    speck = max(MIN_CUTOUT if cell == 1 else math.ceil(MIN_CUTOUT / cell) + 2, SPECK_SHARE * heights[largest])
    large = (areas >= MIN_AREA_SHARE * areas[largest]) & (heights >= MIN_HEIGHT_SHARE * heights[largest])
    large &= sides >= speck
    if not large.any():  # specks only (a noisy alpha): one object, as a single session frames it
        return LayerObjects((LayerObject(bbox, int(areas.sum())),), np.where(labels > 0, 0, -1), cell, bbox[:2])
    groups: list[_Group] = []
    for i in sorted(np.flatnonzero(large), key=lambda i: -areas[i]):
        box = boxes[i]
        home = next((g for g in groups if _inside(g, box)), None)
        if home is None:
            groups.append(_Group([], box[0].start, box[1].start, box[0].stop, box[1].stop, 0))
            home = groups[-1]
        home.take(i + 1, box, int(areas[i]))
    _attach(labels, boxes, areas, groups, [int(i) for i in np.flatnonzero(~large)], speck)
    groups.sort(key=lambda g: -g.area)
    while len(groups) > MAX_OBJECTS:
        extra = groups.pop()
        _attach(labels, boxes, areas, groups, [label - 1 for label in extra.labels], speck, anywhere=True)
        groups.sort(key=lambda g: -g.area)
    lookup = np.full(count + 1, -1, np.int16)
    for index, group in enumerate(groups):
        lookup[group.labels] = index
    cells = lookup[labels]
    left_out = bool(np.any(lookup[1:] < 0))
    x0, y0, x1, y1 = bbox
    objects = []
    for group in groups:
        box = (
            x0 + group.c0 * cell,
            y0 + group.r0 * cell,
            min(x1, x0 + group.c1 * cell),
            min(y1, y0 + group.r1 * cell),
        )
        objects.append(LayerObject(box, group.area))
    return LayerObjects(tuple(objects), cells, cell, (x0, y0), left_out)


def _attach(
    labels: np.ndarray,
    boxes: list,
    areas: np.ndarray,
    groups: list[_Group],
    parts: list[int],
    speck: float,
    anywhere: bool = False,
) -> None:
    """Give each part (an index into ``boxes``, largest first) to the group nearest it when within reach (or
    ``anywhere``); a part out of reach becomes a group of its own, which later parts may join, unless it is a speck
    (its longer side under ``speck`` cells: left out)."""
    distance, nearest = _nearest_groups(labels, groups, len(boxes))
    for i in sorted(parts, key=lambda i: -areas[i]):
        box = boxes[i]
        where = labels[box] == i + 1
        d = distance[box][where]
        k = int(np.argmin(d))
        group = groups[int(nearest[box][where][k])]
        if anywhere or d[k] <= REACH_SHARE * group.height + 1:
            group.take(i + 1, box, int(areas[i]))
        elif max(box[0].stop - box[0].start, box[1].stop - box[1].start) >= speck:  # else left out
            groups.append(_Group([i + 1], box[0].start, box[1].start, box[0].stop, box[1].stop, int(areas[i])))
            distance, nearest = _nearest_groups(labels, groups, len(boxes))


def _nearest_groups(labels: np.ndarray, groups: list[_Group], count: int) -> tuple[np.ndarray, np.ndarray]:
    """For every grid cell, the distance (cells) to the nearest cell of a group and that group's index."""
    owner = np.full(count + 1, -1, np.intp)
    for index, group in enumerate(groups):
        owner[group.labels] = index
    found = ndimage.distance_transform_edt(owner[labels] < 0, return_indices=True)
    distance, (rows, cols) = cast(tuple[np.ndarray, np.ndarray], found)
    return distance, owner[labels[rows, cols]]


__all__ = ["LayerObject", "LayerObjects", "split_objects"]
