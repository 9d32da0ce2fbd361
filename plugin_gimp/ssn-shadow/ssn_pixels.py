"""Pixel formats: which babl format and protocol dtype each GIMP precision uses (GIMP-free).

GIMP stores pixels in one of 18 precisions (u8/u16/u32/half/float/double,
each linear, non-linear or perceptual). The plug-in never reads or writes
pixels in a format it did not name: every Gegl buffer access gives an
explicit babl format, so GIMP/babl convert exactly once and the precision's
transfer curve never leaks into alpha or the shadow.

- Cutout alpha: the layer's alpha as ``"A <type>"`` (alpha is never
  gamma-encoded), the selection mask as ``"Y <type>"`` (GIMP keeps channels
  linear). 8-bit images send u8, every other precision u16: the engine frames
  the cutout into a 256 x 256 frame, so more depth would only cost bytes.
- Shadow layer: the worker's straight-alpha RGBA in the dtype nearest the
  image's precision (u8, u16, half, float; u32 and double get float), written
  as ``"R'G'B'A <type>"``: colour in sRGB perceptual encoding (what a colour
  picker shows), alpha linear. babl converts to the layer's own format (linear
  or perceptual, RGB or grey).
"""

from __future__ import annotations

from dataclasses import dataclass

# GIMP precision component names (from Gimp.Precision value nicks) -> (babl type, protocol dtype)
_LAYER_TYPES = {
    "u8": ("u8", "uint8"),
    "u16": ("u16", "uint16"),
    "u32": ("float", "float32"),
    "half": ("half", "float16"),
    "float": ("float", "float32"),
    "double": ("float", "float32"),
}
_TRCS = ("linear", "non-linear", "perceptual")
BYTES_PER_SAMPLE = {"uint8": 1, "uint16": 2, "float16": 2, "float32": 4}


class PixelFormatError(ValueError):
    """An image precision or type the plug-in does not know."""


@dataclass(frozen=True)
class PixelPlan:
    """Formats for one image: how to read the cutout and write the shadow."""

    precision: str  # GIMP's nick, e.g. "u16-linear"
    alpha_type: str  # babl type of the cutout read, "u8" or "u16"
    alpha_dtype: str  # protocol dtype of the cutout
    layer_type: str  # babl type of the shadow layer data
    layer_dtype: str  # protocol dtype of the shadow layer data

    @property
    def layer_alpha_format(self) -> str:
        return f"A {self.alpha_type}"

    @property
    def selection_format(self) -> str:
        return f"Y {self.alpha_type}"

    @property
    def shadow_format(self) -> str:
        return f"R'G'B'A {self.layer_type}"

    def shadow_nbytes(self, width: int, height: int) -> int:
        return width * height * 4 * BYTES_PER_SAMPLE[self.layer_dtype]


def plan_for_precision(precision_nick: str) -> PixelPlan:
    """The pixel plan for a GIMP precision nick such as ``"u8-non-linear"`` or ``"float-linear"``."""
    component, _, trc = precision_nick.partition("-")
    if component not in _LAYER_TYPES or trc not in _TRCS:
        raise PixelFormatError(f"unsupported image precision {precision_nick!r}")
    layer_type, layer_dtype = _LAYER_TYPES[component]
    alpha_type, alpha_dtype = ("u8", "uint8") if component == "u8" else ("u16", "uint16")
    return PixelPlan(precision_nick, alpha_type, alpha_dtype, layer_type, layer_dtype)


def layer_image_type(base_type_nick: str) -> str:
    """Name of the Gimp.ImageType of the shadow layer for an image base type nick ("rgb"/"gray")."""
    if base_type_nick == "rgb":
        return "RGBA_IMAGE"
    if base_type_nick == "gray":
        return "GRAYA_IMAGE"
    raise PixelFormatError(
        f"Soft Shadow works on RGB and grayscale images, not {base_type_nick!r} ones "
        "(Image > Mode > RGB converts an indexed image)."
    )


def is_blank(data: bytes | bytearray | memoryview) -> bool:
    """True when every byte is zero (an all-transparent alpha in any unsigned or float dtype)."""
    view = memoryview(data).cast("B")
    return not view.tobytes().strip(b"\0") if len(view) else True
