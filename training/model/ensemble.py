"""Ensembles: the mean of several networks' outputs on the same inputs.

The shipped AO map is the mean of two AOPs trained with different recipes: their errors differ by kind of
object (docs/training.md, "AOP ensemble"), and the mean is close to the better of the two on every kind.
"""

from __future__ import annotations

from collections.abc import Sequence

import torch
from torch import nn


class Ensemble(nn.Module):
    """``mean_k net_k(x)`` over the member networks (all of the same module and resolution)."""

    def __init__(self, nets: Sequence[nn.Module]):
        super().__init__()
        if not nets:
            raise ValueError("an ensemble needs at least one network")
        self.nets = nn.ModuleList(nets)

    def forward(self, *inputs: torch.Tensor) -> torch.Tensor:
        out = self.nets[0](*inputs)
        for net in self.nets[1:]:
            out = out + net(*inputs)
        return out / len(self.nets)
