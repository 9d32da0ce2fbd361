"""The light map drawn for the editor (stdlib only): the lights tone-mapped, and the light markers.

Each texel shows its mean radiance under the lights, the light map the
engine gives the model (:func:`.sky_map.map_values`), tone-mapped ``v / (1 + v)``
from night blue to warm white, as packed RGB bytes that a host shows as a
QImage or a GdkPixbuf. Only the rows and columns where a light is above
``CUTOFF`` are visited, so a 192 x 96 picture of a few lights costs a few
milliseconds.

Over it each light has a marker (:func:`marker`): its true extent on the map
(a disk's rim, wider across than down high in the sky; a Gaussian's disk as
wide), or, for a light smaller than ``MIN_MARKER`` pixels there (the sun), a
dotted ring of that radius; and its size as a label ("0.53°",
:func:`.light_size.size_text`). Krita paints the markers with Qt;
:func:`overlay_markers` draws them into the bytes for GIMP, whose Python has
no cairo, the labels in a small pixel font.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

from .light_map import GaussianLight, LightMap, disk_rim
from .light_size import size_text
from .sky_map import map_values

NIGHT = (0.10, 0.13, 0.20)
LIGHT = (1.0, 0.96, 0.85)
PICTURE_SIZE = (192, 96)  # what the editors draw, scaled to the widget
CUTOFF = 1e-3  # a light's factor below which a row or column is left out

MARKER = (255, 255, 255)
SELECTED_MARKER = (255, 200, 0)
GUIDE = (110, 110, 130)
LABEL_SHADE = (20, 20, 30)
MIN_MARKER = 4.0  # pixels: the smallest ring drawn; a light smaller on the map gets a dotted ring of this radius
RIM_POINTS = 72
LABEL_GAP = 3.0  # pixels between a marker and its label
FONT_SCALE = 2  # the pixel font's pixels per glyph dot in overlay_markers

Point = tuple[float, float]

_LUT = [
    bytes(round(255 * (n + (b - n) * k / 255)) for n, b in zip(NIGHT, LIGHT, strict=True)) for k in range(256)
]  # RGB of 256 tone levels


def map_rgb(lights: LightMap, width: int = PICTURE_SIZE[0], height: int = PICTURE_SIZE[1]) -> bytes:
    """RGB888 bytes (height x width x 3) of the tone-mapped light map."""
    dark = _LUT[0] * width
    return b"".join(
        b"".join([_LUT[int(255 * v / (1.0 + v) + 0.5)] for v in row]) if any(row) else dark
        for row in map_values(lights, width, height, CUTOFF)
    )


@dataclass(frozen=True)
class Marker:
    """One light's marker on a ``width`` x ``height`` picture, in pixels of it.

    ``outline``: polylines of the light's true extent, or of a ring of ``MIN_MARKER`` pixels where it is smaller
    (``true_size`` False); x may leave the picture where the map wraps (draw it again a width left or right).
    ``label``: the size; it goes right of the marker, its left end at ``label_x`` and its middle at ``centre``'s
    height, or where that would leave the picture, left of it, its right end at ``label_x_left``.
    """

    centre: Point
    outline: list[list[Point]]
    true_size: bool
    label: str
    label_x: float
    label_x_left: float


def _circle(cx: float, cy: float, radius: float, count: int = 48) -> list[Point]:
    return [
        (cx + radius * math.cos(2 * math.pi * k / count), cy + radius * math.sin(2 * math.pi * k / count))
        for k in range(count)
    ]


def marker(light: GaussianLight, width: int, height: int) -> Marker:
    """The marker of ``light`` on a ``width`` x ``height`` picture of the map."""
    cx, cy = light.u * width, light.v * height
    if light.angle is not None:
        ring = [(u * width, v * height) for u, v in disk_rim(light, RIM_POINTS)]
    else:  # no edge: the disk as wide, round on the map as the Gaussian is
        ring = _circle(cx, cy, light.size_degrees / 2.0 / 90.0 * height, RIM_POINTS)
    true_size = max(math.hypot(x - cx, y - cy) for x, y in ring) >= MIN_MARKER
    if not true_size:
        ring = _circle(cx, cy, MIN_MARKER, 24)
    outline: list[list[Point]] = [[]]
    for point in [*ring, ring[0]]:  # closed; broken where the rim runs over the zenith to the far side
        if outline[-1] and abs(point[0] - outline[-1][-1][0]) > width / 4:
            outline.append([])
        outline[-1].append(point)
    xs = [x for x, _ in ring]
    return Marker((cx, cy), outline, true_size, size_text(light), max(xs) + LABEL_GAP, min(xs) - LABEL_GAP)


# A pixel font for the labels: 5 rows per glyph, '1' a dot.
GLYPHS = {
    "0": ("111", "101", "101", "101", "111"),
    "1": ("01", "11", "01", "01", "01"),
    "2": ("111", "001", "111", "100", "111"),
    "3": ("111", "001", "111", "001", "111"),
    "4": ("101", "101", "111", "001", "001"),
    "5": ("111", "100", "111", "001", "111"),
    "6": ("111", "100", "111", "101", "111"),
    "7": ("111", "001", "001", "001", "001"),
    "8": ("111", "101", "111", "101", "111"),
    "9": ("111", "101", "111", "001", "111"),
    ".": ("0", "0", "0", "0", "1"),
    "\N{DEGREE SIGN}": ("010", "101", "010", "000", "000"),
    "\N{ALMOST EQUAL TO}": ("01100", "10011", "00000", "01100", "10011"),
}


def text_width(text: str, scale: int = FONT_SCALE) -> int:
    """The width in pixels of ``text`` in the pixel font (a dot's gap between glyphs)."""
    return scale * (sum(len(GLYPHS[c][0]) + 1 for c in text) - 1) if text else 0


def _text(rgb: bytearray, width: int, height: int, x: int, y: int, text: str, colour: tuple[int, int, int]) -> None:
    """Draw ``text`` in the pixel font, its top-left corner at (x, y), over a dark shade for contrast."""
    dots = []
    for c in text:
        rows = GLYPHS[c]
        dots += [
            (x + FONT_SCALE * j, y + FONT_SCALE * i)
            for i, row in enumerate(rows)
            for j, d in enumerate(row)
            if d == "1"
        ]
        x += FONT_SCALE * (len(rows[0]) + 1)
    for shade, offsets in ((LABEL_SHADE, (-1, 0, 1)), (colour, (0,))):
        for dx0, dy0 in dots:
            for ox in offsets:
                for oy in offsets:
                    for sx in range(FONT_SCALE):
                        for sy in range(FONT_SCALE):
                            _put(rgb, width, height, dx0 + sx + ox, dy0 + sy + oy, shade)


def _put(rgb: bytearray, width: int, height: int, x: int, y: int, colour: tuple[int, int, int]) -> None:
    if 0 <= y < height:
        x %= width  # the map wraps around in azimuth
        i = 3 * (y * width + x)
        rgb[i : i + 3] = bytes(colour)


def _polyline(rgb: bytearray, width: int, height: int, line: list[Point], colour, dotted: bool) -> None:
    """Draw ``line`` one pixel wide; ``dotted``: two pixels of each three."""
    k = 0
    for a, b in zip(line, line[1:], strict=False):
        steps = max(1, math.ceil(max(abs(b[0] - a[0]), abs(b[1] - a[1]))))
        for i in range(steps):
            if not dotted or k % 3 != 2:
                x, y = round(a[0] + (b[0] - a[0]) * i / steps), round(a[1] + (b[1] - a[1]) * i / steps)
                _put(rgb, width, height, x, y, colour)
            k += 1


def overlay_markers(rgb: bytearray, width: int, height: int, lights: LightMap, selected: int | None) -> bytearray:
    """Draw guides and each light's :func:`marker` (outline, centre cross, size label) onto packed RGB bytes, for
    hosts without a vector painter (GIMP's Python has no cairo).

    Guides: the vertical line at u = 0.5 (the sky behind the object) and the
    quarter lines. Returns ``rgb`` (modified in place).
    """
    for u in (0.25, 0.5, 0.75):
        x = min(width - 1, round(u * width))
        for y in range(0, height, 1 if u == 0.5 else 3):
            _put(rgb, width, height, x, y, GUIDE)
    for index, light in enumerate(lights):
        colour = SELECTED_MARKER if index == selected else MARKER
        m = marker(light, width, height)
        for line in m.outline:
            _polyline(rgb, width, height, line, colour, not m.true_size)
        cx, cy = round(m.centre[0]), round(m.centre[1])
        for d in (-1, 0, 1):  # centre cross
            _put(rgb, width, height, cx + d, cy, colour)
            _put(rgb, width, height, cx, cy + d, colour)
        wide = text_width(m.label)
        x = m.label_x if m.label_x + wide <= width else m.label_x_left - wide
        _text(rgb, width, height, round(x), round(cy - 2.5 * FONT_SCALE), m.label, colour)
    return rgb
