"""The docker's AO edits: brush strokes and grow/shrink steps (protocol ops), with undo of the last one."""

from __future__ import annotations

import copy


class AoEdits:
    """Brush strokes and grow/shrink steps in order (the AO strength is the model's own setting)."""

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
        """The protocol's ``edits`` list: the steps' ops, then ``strength`` unless it is 1."""
        ops = [op for step in self.steps for op in step]
        if strength != 1.0:
            ops.append({"op": "strength", "value": strength})
        return ops
