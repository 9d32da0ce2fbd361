"""The SSN networks: AOP (mask -> AO) and SR (mask + AO + ELM -> shadow)."""

from .ensemble import Ensemble
from .mirror import MirrorAverage
from .unet import AOPNet, SRNet, UNetConfig, build

__all__ = ["AOPNet", "Ensemble", "MirrorAverage", "SRNet", "UNetConfig", "build"]
