"""The list of AO edits a host sends with ``edit_ao`` (stdlib only), with undo of the last stroke or step.

An edit is a protocol op (docs/protocol.md, ``edit_ao``): a brush dab, a grow or shrink step, and, last, one
global strength that scales the occlusion from 0 (none) to :data:`~.defaults.MAX_AO_STRENGTH`; a strength of 1
keeps the predicted AO and sends no op.
"""

from __future__ import annotations

from .defaults import MAX_AO_STRENGTH

__all__ = ["AoEdits", "strength_edits"]


def strength_edits(value: float) -> list[dict]:
    """The edit list's last op for a global AO strength ``value`` in [0, MAX_AO_STRENGTH]: none at 1 (the
    predicted AO kept), else one ``strength`` op."""
    if not 0.0 <= value <= MAX_AO_STRENGTH:
        raise ValueError(f"AO strength: expected 0 to {MAX_AO_STRENGTH:g}, got {value:g}")
    return [] if value == 1.0 else [{"op": "strength", "value": float(value)}]


class AoEdits:
    """Brush strokes and grow/shrink steps in order, plus one global strength (last)."""

    def __init__(self, strength: float = 1.0) -> None:
        self.steps: list[list[dict]] = []  # a brush stroke (several dabs) or one grow op per step
        self.strength = strength

    @property
    def strength(self) -> float:
        return self._strength

    @strength.setter
    def strength(self, value: float) -> None:
        strength_edits(value)  # checks the range
        self._strength = float(value)

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

    def reset(self) -> None:
        self.steps.clear()
        self.strength = 1.0

    def to_list(self) -> list[dict]:
        """The protocol's ``edits`` list."""
        return [op for step in self.steps for op in step] + strength_edits(self.strength)
