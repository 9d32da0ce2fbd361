"""The list of AO edits a host sends with ``edit_ao`` (stdlib only), with undo of the last stroke or step.

An edit is a protocol op (docs/protocol.md, ``edit_ao``): a brush dab, a grow or shrink step, and, last, one
global strength that scales the occlusion from 0 (none) to :data:`~.defaults.MAX_AO_STRENGTH`; a strength of 1
keeps the predicted AO and sends no op.
"""

from __future__ import annotations

import copy

from .defaults import MAX_AO_STRENGTH

__all__ = ["AoEdits", "strength_edits"]


def strength_edits(value: float) -> list[dict]:
    """The edit list's last op for a global AO strength ``value`` in [0, MAX_AO_STRENGTH]: none at 1 (the
    predicted AO kept), else one ``strength`` op."""
    if not 0.0 <= value <= MAX_AO_STRENGTH:
        raise ValueError(f"AO strength: expected 0 to {MAX_AO_STRENGTH:g}, got {value:g}")
    return [] if value == 1.0 else [{"op": "strength", "value": float(value)}]


class AoEdits:
    """Brush strokes and grow/shrink steps in order; the global strength is a setting of its own, appended by
    :meth:`to_list` (:func:`strength_edits`)."""

    def __init__(self, steps: list[list[dict]] | None = None) -> None:
        self.steps: list[list[dict]] = copy.deepcopy(steps) if steps else []  # a stroke (dabs) or one grow op

    def __eq__(self, other: object) -> bool:
        return isinstance(other, AoEdits) and other.steps == self.steps

    def copy(self) -> AoEdits:
        return AoEdits(self.steps)

    def brush(self, x: float, y: float, radius: float, strength: float, new_stroke: bool) -> None:
        dab = {"op": "brush", "x": round(x, 4), "y": round(y, 4), "radius": radius, "strength": strength}
        if new_stroke or not self.steps or self.steps[-1][0]["op"] != "brush":
            self.steps.append([dab])
        else:
            self.steps[-1].append(dab)

    def grow(self, pixels: int) -> None:
        self.steps.append([{"op": "grow", "pixels": int(pixels)}])

    def undo(self) -> bool:
        if self.steps:
            self.steps.pop()
            return True
        return False

    def to_list(self, strength: float = 1.0) -> list[dict]:
        """The protocol's ``edits`` list: the steps' ops, then the global ``strength``'s (none at 1)."""
        return [op for step in self.steps for op in step] + strength_edits(strength)
