"""Shadow methods behind one interface, and the choice of the default one."""

from __future__ import annotations

import os
from dataclasses import dataclass
from pathlib import Path

from .base import ShadowMethod
from .geometric import GeometricCard
from .onnx_ssn import ModelError, OnnxSSN

MODEL_DIR = Path(__file__).resolve().parent.parent / "models"
METHOD_NAMES = ("auto", "ssn", "geometric")


@dataclass(frozen=True)
class LoadedMethod:
    """A method and a sentence saying why it was chosen."""

    method: ShadowMethod
    note: str


def model_dir() -> Path:
    """The model folder: $SSN_SHADOW_MODEL_DIR or the one shipped in the package."""
    return Path(os.environ.get("SSN_SHADOW_MODEL_DIR") or MODEL_DIR)


def load_method(name: str = "auto") -> LoadedMethod:
    """Load 'ssn', 'geometric', or 'auto' (SSN when a valid model is installed, else geometric).

    'ssn' raises ModelError when the model cannot be loaded; 'auto' falls back
    and says why in the note.
    """
    if name not in METHOD_NAMES:
        raise ValueError(f"method: expected one of {', '.join(METHOD_NAMES)}, got {name!r}")
    if name == "geometric":
        return LoadedMethod(GeometricCard(), "geometric card method (requested)")
    folder = model_dir()
    if name == "auto" and not (folder / "model.json").exists():
        return LoadedMethod(
            GeometricCard(), f"no trained SSN model installed ({folder / 'model.json'} missing): geometric card method"
        )
    try:
        method = OnnxSSN(folder)
    except ModelError as exc:
        if name == "ssn":
            raise
        return LoadedMethod(GeometricCard(), f"SSN model unusable ({exc}): geometric card method")
    return LoadedMethod(method, f"SSN model from {folder}")


__all__ = ["GeometricCard", "LoadedMethod", "ModelError", "OnnxSSN", "ShadowMethod", "load_method", "model_dir"]
