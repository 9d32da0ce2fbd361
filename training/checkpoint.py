"""Checkpoints: atomic save, load, and finding the one to resume from."""

from __future__ import annotations

import os
from collections.abc import Sequence
from pathlib import Path
from typing import Any

import torch

from .model import Ensemble, UNetConfig, build

LAST = "last.pt"
BEST = "best.pt"


def save(path: str | Path, state: dict[str, Any]) -> None:
    """Write ``state`` with torch.save to a temporary file, then rename it into place."""
    path = Path(path)
    path.parent.mkdir(parents=True, exist_ok=True)
    tmp = path.with_name(f".{path.name}.tmp-{os.getpid()}")
    torch.save(state, tmp)
    os.replace(tmp, path)


def load(path: str | Path) -> dict[str, Any]:
    return torch.load(Path(path), map_location="cpu", weights_only=False)


def resume_path(run_dir: str | Path) -> Path | None:
    """The run's last checkpoint, if there is one."""
    p = Path(run_dir) / LAST
    return p if p.is_file() else None


def load_model(path: str | Path):
    """Rebuild the network of a checkpoint (eval mode); returns (model, checkpoint dict)."""
    ckpt = load(path)
    model = build(ckpt["module"], UNetConfig.from_dict(ckpt["unet"]))
    model.load_state_dict(ckpt["model"])
    model.eval()
    return model, ckpt


def load_models(paths: Sequence[str | Path]):
    """Rebuild one network, or the :class:`~training.model.Ensemble` of several (same module and resolution);
    returns (model, checkpoint dicts)."""
    loaded = [load_model(p) for p in paths]
    if not loaded:
        raise ValueError("no checkpoint given")
    ckpts = [ck for _, ck in loaded]
    kinds = {(ck["module"], ck["unet"]["resolution"]) for ck in ckpts}
    if len(kinds) > 1:
        raise ValueError(f"checkpoints of different modules or resolutions cannot be averaged: {sorted(kinds)}")
    nets = [net for net, _ in loaded]
    return (nets[0] if len(nets) == 1 else Ensemble(nets).eval()), ckpts
