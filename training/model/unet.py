"""U-Nets of the paper's Section 5.

Encoder stage: 3x3 conv (stride 2 except the first stage) - GroupNorm - ReLU,
then 3x3 conv - GroupNorm - ReLU. Decoder stage: bilinear x2 upsampling,
3x3 conv - GroupNorm - ReLU, concatenation with the encoder activation of the
same scale (skip link), 3x3 conv - GroupNorm - ReLU. A 1x1 conv gives the
output. The SR net flattens the 16 x 32 ELM, repeats it at every bottleneck
location and concatenates it with the bottleneck code before one more
conv - GroupNorm - ReLU.
"""

from __future__ import annotations

from dataclasses import asdict, dataclass

import torch
from torch import nn
from torch.nn import functional as F

ELM_SHAPE = (16, 32)


@dataclass
class UNetConfig:
    """Width per stage (stage 0 at full resolution; len(widths) - 1 downsamplings)."""

    widths: tuple[int, ...] = (8, 16, 32, 64, 96, 128)
    groups: int = 8
    resolution: int = 128
    card: bool = False  # SR only: geometry-guided, takes the geometric card's shadow (SRNet)
    camera: bool = False  # AOP only: takes the camera input as ground-geometry channels (AOPNet)
    outputs: int = 1  # output channels (the surface model's: the visible surface's pixel height and the depth)

    @property
    def depth(self) -> int:
        return len(self.widths) - 1

    def to_dict(self) -> dict:
        d = asdict(self)
        d["widths"] = list(self.widths)
        return d

    @classmethod
    def from_dict(cls, d: dict) -> UNetConfig:
        return cls(
            widths=tuple(d["widths"]),
            groups=d["groups"],
            resolution=d["resolution"],
            card=d.get("card", False),
            camera=d.get("camera", False),
            outputs=d.get("outputs", 1),
        )


def _norm(channels: int, groups: int) -> nn.GroupNorm:
    g = groups
    while channels % g:
        g -= 1
    return nn.GroupNorm(g, channels)


class ConvNormReLU(nn.Sequential):
    """3x3 conv (optionally strided), GroupNorm, ReLU."""

    def __init__(self, cin: int, cout: int, groups: int, stride: int = 1):
        super().__init__(
            nn.Conv2d(cin, cout, 3, stride=stride, padding=1, bias=False),
            _norm(cout, groups),
            nn.ReLU(inplace=True),
        )


class Down(nn.Sequential):
    """Encoder stage: strided conv block then a conv block."""

    def __init__(self, cin: int, cout: int, groups: int, stride: int):
        super().__init__(ConvNormReLU(cin, cout, groups, stride), ConvNormReLU(cout, cout, groups))


class Up(nn.Module):
    """Decoder stage: bilinear x2, conv block, concat skip, conv block."""

    def __init__(self, cin: int, cout: int, groups: int):
        super().__init__()
        self.reduce = ConvNormReLU(cin, cout, groups)
        self.fuse = ConvNormReLU(2 * cout, cout, groups)

    def forward(self, x: torch.Tensor, skip: torch.Tensor) -> torch.Tensor:
        x = F.interpolate(x, size=skip.shape[-2:], mode="bilinear", align_corners=False)
        return self.fuse(torch.cat([self.reduce(x), skip], dim=1))


class UNet(nn.Module):
    """Encoder-decoder with skip links; ``bottleneck_extra`` channels are concatenated at the bottleneck."""

    def __init__(self, in_channels: int, config: UNetConfig, bottleneck_extra: int = 0):
        super().__init__()
        w, g = config.widths, config.groups
        self.config = config
        self.encoder = nn.ModuleList(
            [Down(in_channels if i == 0 else w[i - 1], w[i], g, 1 if i == 0 else 2) for i in range(len(w))]
        )
        self.inject = ConvNormReLU(w[-1] + bottleneck_extra, w[-1], g) if bottleneck_extra else None
        self.decoder = nn.ModuleList([Up(w[i], w[i - 1], g) for i in range(len(w) - 1, 0, -1)])
        self.head = nn.Conv2d(w[0], config.outputs, 1)

    def forward(self, x: torch.Tensor, code: torch.Tensor | None = None) -> torch.Tensor:
        skips = []
        for stage in self.encoder:
            x = stage(x)
            skips.append(x)
        if self.inject is not None:
            assert code is not None
            b, _, h, w = x.shape
            x = self.inject(torch.cat([x, code[:, :, None, None].expand(b, code.shape[1], h, w)], dim=1))
        for stage, skip in zip(self.decoder, reversed(skips[:-1]), strict=True):
            x = stage(x, skip)
        return self.head(x)


FOCAL_CENTRE = 1.2  # a focal length of 1.2 frames (a 45 degree field of view) enters the focal channel as 0


def camera_maps(camera: torch.Tensor, r: int) -> torch.Tensor:
    """Ground-geometry channels (B, 2, R, R) of camera inputs (B, 2), horizon row and focal length in frames: each
    pixel row's offset below the horizon and the focal length less ``FOCAL_CENTRE``. Which rows see the ground,
    and how steeply it recedes there, is what a mask alone cannot tell under a level camera."""
    b = camera.shape[0]
    rows = (torch.arange(r, dtype=camera.dtype, device=camera.device) + 0.5) / r
    below = rows[None, None, :, None] - camera[:, 0, None, None, None]
    focal = camera[:, 1, None, None, None] - FOCAL_CENTRE
    return torch.cat([below.expand(b, 1, r, r), focal.expand(b, 1, r, r)], dim=1)


class AOPNet(nn.Module):
    """Ambient-occlusion prediction: mask (B, 1, R, R) -> AO (B, 1, R, R), linear output; with ``config.camera``
    also the camera input (B, 2) in frames (horizon row / N, focal length / N), as :func:`camera_maps`."""

    def __init__(self, config: UNetConfig):
        super().__init__()
        self.config = config
        self.unet = UNet(3 if config.camera else 1, config)

    def forward(self, mask: torch.Tensor, camera: torch.Tensor | None = None) -> torch.Tensor:
        if not self.config.camera:
            return self.unet(mask)
        assert camera is not None, "this AOP takes the camera input"
        return self.unet(torch.cat([mask, camera_maps(camera, mask.shape[-1])], dim=1))


class SRNet(nn.Module):
    """Shadow rendering: mask, AO (B, 1, R, R) and ELM (B, 16, 32) -> target map (B, 1, R, R), linear output.

    Geometry-guided (``config.card``): the geometric card's shadow for the same ELM (B, 1, R, R) is a third
    input channel and the base of the output, so the network learns a correction of the card's shadow
    (contact, softness, the shape's true silhouette on the ground) while direction and length come from
    the card's geometry.
    """

    def __init__(self, config: UNetConfig):
        super().__init__()
        self.config = config
        self.unet = UNet(3 if config.card else 2, config, bottleneck_extra=ELM_SHAPE[0] * ELM_SHAPE[1])

    def forward(
        self, mask: torch.Tensor, ao: torch.Tensor, elm: torch.Tensor, card: torch.Tensor | None = None
    ) -> torch.Tensor:
        if not self.config.card:
            return self.unet(torch.cat([mask, ao], dim=1), elm.flatten(1))
        assert card is not None, "this SR takes the card's shadow"
        return card + self.unet(torch.cat([mask, ao, card], dim=1), elm.flatten(1))


def build(module: str, config: UNetConfig, head_bias: float | None = None) -> AOPNet | SRNet:
    """AOPNet or SRNet for ``module`` in {"aop", "sr"}; ``head_bias`` sets the output's initial offset
    (the typical target value: 1 for AO, 0 for s), so the linear head does not spend its first
    thousand Adam steps moving a bias."""
    if module == "aop":
        net: AOPNet | SRNet = AOPNet(config)
    elif module == "sr":
        net = SRNet(config)
    else:
        raise ValueError(f"module must be 'aop' or 'sr', got {module!r}")
    bias = net.unet.head.bias
    if head_bias is not None and bias is not None:
        with torch.no_grad():
            bias.fill_(head_bias)
    return net
