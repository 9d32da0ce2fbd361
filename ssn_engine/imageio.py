"""Reading and writing images with clear errors."""

from __future__ import annotations

from pathlib import Path

import numpy as np
from PIL import Image, UnidentifiedImageError


class ImageFileError(ValueError):
    """An image file is missing, unreadable or of an unsupported kind."""


def load_rgba(path: str | Path) -> np.ndarray:
    """An image file as RGBA uint8 (H, W, 4); images without alpha get an opaque one."""
    path = Path(path)
    try:
        with Image.open(path) as im:
            im.load()
            if im.mode in ("I;16", "I;16B", "I"):
                im = im.point(lambda v: v / 257).convert("L")
            return np.asarray(im.convert("RGBA"))
    except FileNotFoundError:
        raise ImageFileError(f"{path}: no such file") from None
    except (UnidentifiedImageError, OSError, SyntaxError, ValueError) as exc:
        raise ImageFileError(f"{path}: not a readable image ({exc})") from None


def save_png(path: str | Path, image: np.ndarray) -> Path:
    """Write uint8 or uint16 RGB(A)/grey data as PNG (16-bit only for grey)."""
    path = Path(path)
    if path.parent and not path.parent.exists():
        raise ImageFileError(f"{path}: folder {path.parent} does not exist")
    try:
        Image.fromarray(image).save(path, format="PNG")
    except OSError as exc:
        raise ImageFileError(f"{path}: cannot write ({exc})") from None
    return path
