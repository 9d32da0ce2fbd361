"""The AO an SR trains on in use (``train --ao-from``, ``--ao-from-camera``): an AOP's predictions, from its
checkpoints (their ensemble) or an exported graph."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import torch

from ssn_engine.methods.onnx_ssn import _session

from . import checkpoint

__all__ = ["OnnxAOP", "load_aop"]


class OnnxAOP:
    """An exported AOP graph (aop.onnx, or aop_camera.onnx with ``camera``) called like the torch AOP: mask tensor
    (B, 1, R, R) (and camera inputs (B, 2) in frames) -> AO tensor."""

    def __init__(self, path: str, camera: bool = False):
        self.session = _session(Path(path), "aop_camera" if camera else "aop")

    def __call__(self, mask: torch.Tensor, camera: torch.Tensor | None = None) -> torch.Tensor:
        feeds = {"mask": mask.numpy().astype(np.float32)}
        if camera is not None:
            feeds["camera"] = camera.numpy().astype(np.float32)
        return torch.from_numpy(self.session.run(["ao"], feeds)[0])


def load_aop(paths: list[str], camera: bool = False):
    """The AO predictor --ao-from (``camera``: --ao-from-camera) names, checkpoints (their ensemble) or one exported
    aop.onnx (aop_camera.onnx) graph, as a function of masks (B, R, R) (and camera inputs (B, 2) in frames) -> AO
    maps (B, R, R) for the view cache (each view's AO is predicted once)."""
    if len(paths) == 1 and paths[0].endswith(".onnx"):
        net = OnnxAOP(paths[0], camera)
    else:
        net, ckpts = checkpoint.load_models(paths)
        if any(bool(ck["unet"].get("camera", False)) != camera for ck in ckpts):
            raise ValueError(f"{paths}: expected AOP checkpoints {'with' if camera else 'without'} the camera input")

    @torch.no_grad()
    def predict(masks: np.ndarray, cameras: np.ndarray | None = None) -> np.ndarray:
        inputs = [torch.from_numpy(np.ascontiguousarray(masks[:, None], np.float32))]
        if cameras is not None:
            inputs.append(torch.from_numpy(np.asarray(cameras, np.float32)))
        return net(*inputs)[:, 0].clamp(0, 1).numpy()

    return predict
