"""The training losses: per-pixel L2 to the module's target, plus a weight of 1 - ZNCC (``train --zncc-weight``)."""

from __future__ import annotations

import torch
from torch.nn import functional as F

__all__ = ["Objective", "target_of", "zncc_loss"]


def target_of(module: str, x: dict[str, torch.Tensor]) -> torch.Tensor:
    """The batch's target of ``module``: the AO map (AOP) or the light-dependent target (SR)."""
    return x["ao"] if module == "aop" else x["target"]


def zncc_loss(pred: torch.Tensor, target: torch.Tensor, eps: float = 1e-6) -> torch.Tensor:
    """Mean 1 - ZNCC of (B, 1, H, W) maps, each image on its own (as :func:`training.metrics.zncc`; ``eps`` keeps a
    shadowless target finite): every image counts alike, where L2 lets the large dark shadows of low suns and broad
    skies outweigh a high sun's small one."""
    p, t = pred.flatten(1), target.flatten(1)
    p, t = p - p.mean(dim=1, keepdim=True), t - t.mean(dim=1, keepdim=True)
    corr = (p * t).sum(dim=1) / (p.norm(dim=1) * t.norm(dim=1) + eps)
    return (1.0 - corr).mean()


class Objective:
    """The loss: per-pixel L2 to the module's target, plus ``zncc_weight`` x its 1 - ZNCC (each image on its own)."""

    def __init__(self, module: str, zncc_weight: float = 0.0):
        self.module, self.zncc_weight = module, zncc_weight

    def __call__(self, pred: torch.Tensor, x: dict[str, torch.Tensor]) -> torch.Tensor:
        target = target_of(self.module, x)
        loss = F.mse_loss(pred, target)
        if self.zncc_weight:
            loss = loss + self.zncc_weight * zncc_loss(pred, target)
        return loss
