"""The SSN networks: AOP (mask -> AO) and SR (mask + AO + ELM -> shadow)."""

from .unet import AOPNet, SRNet, UNetConfig, build

__all__ = ["AOPNet", "SRNet", "UNetConfig", "build"]
