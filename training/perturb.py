"""The SR module's AO input augmentation: random grey erosion or dilation of the ground-truth AO map."""

from __future__ import annotations

import torch
from torch.nn import functional as F

SIZES = (3, 5, 7)


def perturb_ao(
    ao: torch.Tensor, generator: torch.Generator | None = None, sizes: tuple[int, ...] = SIZES
) -> torch.Tensor:
    """Per sample of (B, 1, R, R): unchanged, eroded (dark contact regions grow) or dilated (they shrink),
    each with probability 1/3, with a square structuring element of a random size in ``sizes``."""
    out = ao.clone()
    ops = torch.randint(0, 3, (ao.shape[0],), generator=generator)
    ks = torch.randint(0, len(sizes), (ao.shape[0],), generator=generator)
    for b in range(ao.shape[0]):
        op, k = int(ops[b]), sizes[int(ks[b])]
        if op == 0:
            continue
        x = ao[b : b + 1]
        if op == 1:  # erosion: min filter
            out[b : b + 1] = -F.max_pool2d(-x, k, stride=1, padding=k // 2)
        else:  # dilation: max filter
            out[b : b + 1] = F.max_pool2d(x, k, stride=1, padding=k // 2)
    return out
