"""The docker's list of AO edits (protocol ops), with undo of the last stroke or step."""

from __future__ import annotations


class AoEdits:
    """Brush strokes and grow/shrink steps in order, plus one global strength (last)."""

    def __init__(self) -> None:
        self.steps: list[list[dict]] = []  # a brush stroke (several dabs) or one grow op per step
        self.strength = 1.0

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
        ops = [op for step in self.steps for op in step]
        if self.strength != 1.0:
            ops.append({"op": "strength", "value": self.strength})
        return ops
