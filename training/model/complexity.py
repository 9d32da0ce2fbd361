"""Parameter and multiply-add counts per module, from forward hooks on conv, norm and linear layers."""

from __future__ import annotations

import torch
from torch import nn


def count_parameters(model: nn.Module) -> int:
    return sum(p.numel() for p in model.parameters())


def count_macs(model: nn.Module, *inputs: torch.Tensor) -> int:
    """Multiply-adds of one forward pass on ``inputs`` (convolutions and linear layers; norms count one per element)."""
    total = 0

    def conv_hook(m: nn.Conv2d, _inp, out: torch.Tensor) -> None:
        nonlocal total
        k = m.kernel_size[0] * m.kernel_size[1] * (m.in_channels // m.groups)
        total += out.numel() * k

    def norm_hook(_m, _inp, out: torch.Tensor) -> None:
        nonlocal total
        total += out.numel()

    hooks = []
    for m in model.modules():
        if isinstance(m, nn.Conv2d):
            hooks.append(m.register_forward_hook(conv_hook))
        elif isinstance(m, nn.GroupNorm):
            hooks.append(m.register_forward_hook(norm_hook))
    try:
        with torch.no_grad():
            model(*inputs)
    finally:
        for h in hooks:
            h.remove()
    return total // inputs[0].shape[0]


def describe(module: str, model: nn.Module, resolution: int) -> str:
    """One line: parameters and multiply-adds per image at ``resolution``."""
    mask = torch.zeros(1, 1, resolution, resolution)
    inputs = (mask,) if module == "aop" else (mask, mask, torch.zeros(1, 16, 32))
    config = getattr(model, "config", None)
    if module == "sr" and config is not None and config.card:
        inputs += (mask,)
    if module == "aop" and config is not None and config.camera:
        inputs += (torch.tensor([[0.5, 1.2]]),)
    was_training = model.training
    model.eval()
    macs = count_macs(model, *inputs)
    model.train(was_training)
    return (
        f"{module.upper()}: {count_parameters(model) / 1e6:.3f} M parameters, "
        f"{macs / 1e9:.3f} G multiply-adds per {resolution}x{resolution} image"
    )
