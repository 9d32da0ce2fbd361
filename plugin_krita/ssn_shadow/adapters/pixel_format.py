"""Krita pixel formats and the byte shuffling the plug-in needs (no numpy).

Krita stores RGBA U8 and U16 pixels as B, G, R, A and F16/F32 pixels as
R, G, B, A, little-endian; alpha is always the fourth channel.
"""

from __future__ import annotations

from dataclasses import dataclass

# depth -> (protocol dtype, bytes per channel, channel order in memory)
DEPTHS: dict[str, tuple[str, int, str]] = {
    "U8": ("uint8", 1, "bgra"),
    "U16": ("uint16", 2, "bgra"),
    "F16": ("float16", 2, "rgba"),
    "F32": ("float32", 4, "rgba"),
}


class UnsupportedFormat(ValueError):
    """The document's colour model or depth is not one the plug-in handles."""


@dataclass(frozen=True)
class PixelFormat:
    """One Krita RGBA pixel layout."""

    depth: str
    dtype: str
    itemsize: int
    channels: str

    @property
    def pixel_size(self) -> int:
        return 4 * self.itemsize

    def render_format(self) -> dict[str, str]:
        """The protocol's ``format`` field for layers in this layout."""
        return {"dtype": self.dtype, "channels": self.channels}


def pixel_format(color_model: str, color_depth: str) -> PixelFormat:
    """The layout of an RGBA document; UnsupportedFormat with a message for people otherwise."""
    if color_model != "RGBA" or color_depth not in DEPTHS:
        raise UnsupportedFormat(
            f"Soft Shadow works on RGB/Alpha images (8 or 16 bit integer, 16 or 32 bit float); "
            f"this image is {color_model}/{color_depth}. "
            "Convert it with Image > Convert Image Color Space, or work on an RGBA copy."
        )
    dtype, itemsize, channels = DEPTHS[color_depth]
    return PixelFormat(color_depth, dtype, itemsize, channels)


def extract_alpha(data: bytes | bytearray, fmt: PixelFormat) -> bytes:
    """The alpha channel of interleaved RGBA pixels, as raw bytes of ``fmt.dtype``."""
    n, ps = fmt.itemsize, fmt.pixel_size
    if len(data) % ps:
        raise ValueError(f"pixel data of {len(data)} bytes is not a whole number of {ps}-byte pixels")
    if n == 1:
        return bytes(data[3::4])
    out = bytearray(len(data) // 4)
    for k in range(n):
        out[k::n] = data[3 * n + k :: ps]
    return bytes(out)


def place_rows(region: bytes, x: int, y: int, w: int, h: int, canvas_w: int, canvas_h: int, itemsize: int) -> bytearray:
    """A canvas-sized single-channel plane (zeros) with ``region`` (w x h at x, y) copied in."""
    plane = bytearray(canvas_w * canvas_h * itemsize)
    row = w * itemsize
    if len(region) != row * h:
        raise ValueError(f"region of {len(region)} bytes does not match {w} x {h} x {itemsize}")
    if x == 0 and w == canvas_w:
        plane[y * row : (y + h) * row] = region
        return plane
    stride = canvas_w * itemsize
    for r in range(h):
        start = (y + r) * stride + x * itemsize
        plane[start : start + row] = region[r * row : (r + 1) * row]
    return plane


# The most significant byte of an alpha sample at least half opaque (little-endian): unsigned integers from 0x80,
# half floats from 0x38 (0.5 = 0x3800), floats from 0x3F (0.5 = 0x3F000000); the sign bit clear for floats.
HALF_OPAQUE_TOP_BYTE = {"uint8": (0x80, 0xFF), "uint16": (0x80, 0xFF), "float16": (0x38, 0x7F), "float32": (0x3F, 0x7F)}


def opaque_everywhere(alpha: bytes, dtype: str) -> bool:
    """True when no pixel of a canvas alpha plane is more than half transparent: it holds no cutout. Byte
    operations only (C speed: a 4000 x 3000 plane in milliseconds, where a Python loop took about half a
    second)."""
    if not alpha:
        return False
    size = {"uint8": 1, "uint16": 2, "float16": 2, "float32": 4}[dtype]
    lo, hi = HALF_OPAQUE_TOP_BYTE[dtype]
    top = bytes(alpha[size - 1 :: size])
    return not top.translate(None, bytes(range(lo, hi + 1)))  # nothing left: every top byte in range


Rect = tuple[int, int, int, int]  # x, y, width, height


def clip_rect(x: int, y: int, w: int, h: int, canvas_w: int, canvas_h: int) -> Rect:
    """A rectangle clipped to the canvas (width or height 0 when outside)."""
    x0, y0 = max(0, x), max(0, y)
    x1, y1 = min(canvas_w, x + w), min(canvas_h, y + h)
    return x0, y0, max(0, x1 - x0), max(0, y1 - y0)


def rect_difference(a: Rect, b: Rect) -> list[Rect]:
    """The parts of rect ``a`` outside rect ``b``: at most four non-empty rects (bands above and below ``b``,
    then left and right of it)."""
    ax, ay, aw, ah = a
    if aw <= 0 or ah <= 0:
        return []
    bx, by, bw, bh = b
    x0, y0, x1, y1 = max(ax, bx), max(ay, by), min(ax + aw, bx + bw), min(ay + ah, by + bh)
    if bw <= 0 or bh <= 0 or x1 <= x0 or y1 <= y0:
        return [a]
    parts = [
        (ax, ay, aw, y0 - ay),
        (ax, y1, aw, ay + ah - y1),
        (ax, y0, x0 - ax, y1 - y0),
        (x1, y0, ax + aw - x1, y1 - y0),
    ]
    return [p for p in parts if p[2] > 0 and p[3] > 0]


def srgb_to_linear(c: float) -> float:
    """One sRGB-encoded component in [0, 1] to linear light."""
    return c / 12.92 if c <= 0.04045 else ((c + 0.055) / 1.055) ** 2.4


def is_linear_profile(profile: str) -> bool:
    """Whether a Krita profile name is a linear-gamma one (e.g. 'sRGB-elle-V2-g10.icc')."""
    p = profile.lower()
    return "g10" in p or "linear" in p or "scrgb" in p


def shadow_color(rgb: tuple[float, float, float], profile: str) -> list[float]:
    """The shadow colour (picked as sRGB) in the document's encoding."""
    if is_linear_profile(profile):
        return [round(srgb_to_linear(c), 6) for c in rgb]
    return [float(c) for c in rgb]


def blend_mode(rgb: tuple[float, float, float]) -> str:
    """The shadow layer's blend mode for a shadow colour: Multiply tints what lies under the shadow; a black
    shadow (the default) is Normal, whose composite over a background is the same, background * (1 - alpha),
    and which Krita 5.1 composites 2.5 to 5 times faster (Multiply at F16 is scalar code: adding a 1800 x 900
    shadow layer took 112 ms against 21 ms in Normal, at U8 18 against 7 ms)."""
    return "normal" if not any(rgb) else "multiply"
