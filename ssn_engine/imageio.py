"""Reading and writing images with clear errors; every write is atomic.

Reading checks an image's size before decoding it (``max_megapixels``, instead of Pillow's decompression-bomb
error or warning). Writing goes through :func:`atomic_writes`: each image is written to a temporary file beside
its destination, and all are renamed into place only when every one was written, so an interrupted or failed run
leaves neither a partial file nor a damaged old one. A replaced file keeps its permissions, and a symbolic link
is written through: its target gets the image and the link stays.
"""

from __future__ import annotations

import contextlib
import os
import stat
import tempfile
import warnings
from collections.abc import Callable, Iterator
from pathlib import Path

import numpy as np
from PIL import Image, UnidentifiedImageError

from .stripes import row_stripes

DEFAULT_MAX_MEGAPIXELS = 200.0
ALPHA_MODES = ("RGBA", "LA", "PA", "RGBa", "La")


class ImageFileError(ValueError):
    """An image file is missing, unreadable, too large or of an unsupported kind, or cannot be written."""


def _rgba_array(im: Image.Image) -> np.ndarray:
    """A writable RGBA uint8 copy of a decoded image, converted in stripes: the only canvas-sized buffers are
    the decoded image and the array (a whole-image conversion would add two more)."""
    w, h = im.size
    out = np.empty((h, w, 4), np.uint8)
    for rows in row_stripes(0, h, w):
        part = im.crop((0, rows.start, w, rows.stop))
        out[rows] = np.asarray(part if part.mode == "RGBA" else part.convert("RGBA"))
    return out


@contextlib.contextmanager
def _size_checked_here() -> Iterator[None]:
    """Pillow's own decompression-bomb check off: :func:`load_image` checks the size itself."""
    limit = Image.MAX_IMAGE_PIXELS
    Image.MAX_IMAGE_PIXELS = None
    try:
        with warnings.catch_warnings():
            warnings.simplefilter("ignore", Image.DecompressionBombWarning)
            yield
    finally:
        Image.MAX_IMAGE_PIXELS = limit


def load_image(path: str | Path, max_megapixels: float = DEFAULT_MAX_MEGAPIXELS) -> tuple[np.ndarray, bool]:
    """An image file as a writable RGBA uint8 array (H, W, 4) and whether the file has an alpha channel (without
    one, the alpha is opaque). Images above ``max_megapixels`` are refused before they are decoded."""
    path = Path(path)
    try:
        if path.is_file() and path.stat().st_size == 0:
            raise ImageFileError(f"{path}: empty file (0 bytes), not an image")
        with _size_checked_here(), Image.open(path) as im:
            w, h = im.size
            if w * h > max_megapixels * 1e6:
                raise ImageFileError(
                    f"{path}: {w} x {h} is {w * h / 1e6:.3g} megapixels, above the limit of {max_megapixels:g}; "
                    f"pass --max-megapixels {int(np.ceil(w * h / 1e6))} to allow it (it needs about "
                    f"{max(1, round(w * h * 15 / 2**20)):,} MiB of memory)"
                )
            im.load()
            has_alpha = im.mode in ALPHA_MODES or "transparency" in im.info
            if im.mode in ("I;16", "I;16B", "I"):
                im = im.point(lambda v: v / 257).convert("L")
            return _rgba_array(im), has_alpha
    except FileNotFoundError:
        raise ImageFileError(f"{path}: no such file") from None
    except IsADirectoryError:
        raise ImageFileError(f"{path}: is a folder, not an image") from None
    except (UnidentifiedImageError, OSError, SyntaxError, ValueError) as exc:
        if isinstance(exc, ImageFileError):
            raise
        raise ImageFileError(f"{path}: not a readable image ({exc})") from None


def _umask() -> int:
    mask = os.umask(0)
    os.umask(mask)
    return mask


def _mode(target: Path) -> int:
    """The permissions of the file ``target`` replaces, or the usual ones (0666 less the umask) for a new file."""
    try:
        return stat.S_IMODE(target.stat().st_mode)
    except FileNotFoundError:
        return 0o666 & ~_umask()


@contextlib.contextmanager
def atomic_writes(placed: list[Path] | None = None) -> Iterator[Callable[[str | Path, np.ndarray], Path]]:
    """Yield ``write(path, image)``, which writes a PNG (uint8 RGB(A)/grey, or uint16 grey) to a temporary file
    beside ``path`` (beside a symbolic link's target). When the block ends normally all of them are renamed into
    place, each appended to ``placed`` once it is; when it raises (a failed write, a full disk, Ctrl+C) every
    temporary file is removed and no destination is touched. A replaced file keeps its permissions."""
    staged: list[tuple[Path, Path, Path]] = []  # (temporary file, where it goes, the path as given)

    def write(path: str | Path, image: np.ndarray) -> Path:
        path = Path(path)
        target = Path(os.path.realpath(path))  # a symbolic link's target gets the image; the link stays
        try:
            fd, tmp = tempfile.mkstemp(prefix=f".{target.name}.", suffix=".part", dir=target.parent)
        except OSError as exc:
            raise ImageFileError(f"{path}: cannot write ({exc.strerror or exc})") from None
        staged.append((Path(tmp), target, path))
        try:
            with os.fdopen(fd, "wb") as stream:
                Image.fromarray(image).save(stream, format="PNG")
            os.chmod(tmp, _mode(target))  # mkstemp's files are private
        except OSError as exc:
            raise ImageFileError(f"{path}: cannot write ({exc.strerror or exc}); nothing was written") from None
        return path

    try:
        yield write
        for tmp, target, path in staged:
            os.replace(tmp, target)
            if placed is not None:
                placed.append(path)
    finally:
        for tmp, _, _ in staged:
            tmp.unlink(missing_ok=True)
