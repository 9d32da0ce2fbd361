"""Mirror averaging: a network's output averaged with that of its mirrored input, mirrored back.

Every image input mirrors with a flip of its last axis: frames in x, the 16 x 32 light map in azimuth
(``training.batches.mirror``); an input of one value per sample and channel ((b, k): the camera input, horizon
row and focal length) is the same for the mirrored scene (the camera has no roll) and passes unchanged. The
scene's mirror symmetry makes the two passes equally valid estimates, so their mean is the network's
mirror-symmetric part: it cancels the left-right bias the network has learned.
"""

from __future__ import annotations

import torch
from torch import nn


class MirrorAverage(nn.Module):
    """``0.5 * (net(x) + mirror(net(mirror(x))))``, both passes in one batch (inputs of two dimensions, (b, k),
    unmirrored)."""

    def __init__(self, net: nn.Module):
        super().__init__()
        self.net = net

    def forward(self, *inputs: torch.Tensor) -> torch.Tensor:
        n = inputs[0].shape[0]
        out = self.net(*(torch.cat([x, x.flip(-1) if x.dim() > 2 else x]) for x in inputs))
        return 0.5 * (out[:n] + out[n:].flip(-1))
