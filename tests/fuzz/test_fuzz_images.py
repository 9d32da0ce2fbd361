"""The image reader on PNG, JPEG and TIFF files of every mode and depth, whole, truncated or corrupted: an RGBA
array or an ImageFileError, and the file is never changed."""

from __future__ import annotations

import hashlib
import io

import numpy as np
import pytest
from fuzz_settings import FUZZ
from hypothesis import assume, given
from hypothesis import strategies as st
from PIL import Image

from ssn_engine.imageio import ImageFileError, load_image

MODES = ["1", "L", "LA", "P", "PA", "RGB", "RGBA", "CMYK", "YCbCr", "I", "I;16", "F", "LAB", "HSV"]
FORMATS = ["PNG", "JPEG", "TIFF"]


def encoded(mode: str, fmt: str, w: int, h: int, seed: int) -> bytes | None:
    """An image of that mode and size as a file of that format, or None where Pillow cannot write it."""
    rng = np.random.default_rng(seed)
    base = Image.fromarray(rng.integers(0, 256, (h, w, 4), dtype=np.uint8), "RGBA")
    try:
        im = (
            base.convert(mode)
            if mode not in ("I;16", "LAB", "HSV")
            else base.convert("L" if mode == "I;16" else "RGB").convert(mode)
        )
        if mode == "P":
            im.info["transparency"] = 0
        buf = io.BytesIO()
        im.save(buf, format=fmt)
        return buf.getvalue()
    except (OSError, ValueError, KeyError):
        return None


@FUZZ
@given(
    mode=st.sampled_from(MODES),
    fmt=st.sampled_from(FORMATS),
    w=st.integers(1, 40),
    h=st.integers(1, 40),
    seed=st.integers(0, 1000),
    damage=st.sampled_from(["none", "truncate", "flip", "garbage"]),
    where=st.floats(0, 1),
)
def test_any_image_file(tmp_path_factory, mode, fmt, w, h, seed, damage, where):
    data = encoded(mode, fmt, w, h, seed)
    assume(data is not None)
    cut = int(where * len(data))
    if damage == "truncate":
        data = data[:cut]
    elif damage == "flip":
        data = data[:cut] + bytes([data[cut] ^ 0xFF]) + data[cut + 1 :] if cut < len(data) else data
    elif damage == "garbage":
        data = data[:cut] + np.random.default_rng(seed).integers(0, 256, 64, dtype=np.uint8).tobytes()
    path = tmp_path_factory.mktemp("img") / f"input.{fmt.lower()}"
    path.write_bytes(data)
    digest = hashlib.sha256(data).hexdigest()
    try:
        rgba, has_alpha = load_image(path)
    except ImageFileError as exc:
        assert str(path) in str(exc)
    else:
        assert rgba.dtype == np.uint8 and rgba.ndim == 3 and rgba.shape[2] == 4 and isinstance(has_alpha, bool)
        assert rgba.flags.writeable
        if damage == "none":
            assert rgba.shape[:2] == (h, w)
    assert hashlib.sha256(path.read_bytes()).hexdigest() == digest


@pytest.mark.parametrize("mode", MODES)
def test_every_mode_that_pillow_writes_reads_back(tmp_path, mode):
    for fmt in FORMATS:
        data = encoded(mode, fmt, 7, 5, 0)
        if data is None:
            continue
        path = tmp_path / f"x.{fmt.lower()}"
        path.write_bytes(data)
        rgba, has_alpha = load_image(path)
        assert rgba.shape == (5, 7, 4)
        assert has_alpha == (mode in ("LA", "PA", "RGBA", "P") and fmt != "JPEG") or fmt == "TIFF"
