"""How the dialog lays out its two columns on the screen it opens on (GIMP-free).

Side by side (the light map and its fields beside the preview) the dialog is
about 800 pixels wide and 650 tall: it fits a 1366 x 768 screen, but not a
768-pixel-wide one (a 768 x 1366 portrait screen, a small tablet), where OK
would lie past the screen's right edge. There the columns are stacked, the
preview under the light map, about 480 pixels wide; where even that is too
tall (or too wide) for the screen, the dialog's contents scroll.
"""

from __future__ import annotations

from dataclasses import dataclass

# What a window manager adds around the dialog (borders, a title bar), pixels (width, height); the screen's work
# area (the monitor's, less its panels) must hold the dialog with these around it.
FRAME = (16, 48)


@dataclass(frozen=True)
class Layout:
    """``stacked``: the preview under the light map, not beside it; ``scrolled``: the contents scroll, so that the
    whole dialog is at most ``max_width`` x ``max_height`` pixels."""

    stacked: bool
    scrolled: bool = False
    max_width: int = 0
    max_height: int = 0


def choose_layout(side_by_side: tuple[int, int], stacked: tuple[int, int], work_area: tuple[int, int]) -> Layout:
    """The layout for a dialog of natural size ``side_by_side`` (width, height) with its columns side by side and
    ``stacked`` with them stacked, on a screen whose work area is ``work_area`` (width, height): side by side
    where it fits (with :data:`FRAME` around it), else stacked where that fits, else scrolled: side by side where
    that is as wide as the screen allows (only too tall), else stacked."""
    room = (work_area[0] - FRAME[0], work_area[1] - FRAME[1])

    def fits(size: tuple[int, int]) -> bool:
        return size[0] <= room[0] and size[1] <= room[1]

    if fits(side_by_side):
        return Layout(stacked=False)
    if fits(stacked):
        return Layout(stacked=True)
    return Layout(stacked=side_by_side[0] > room[0], scrolled=True, max_width=room[0], max_height=room[1])
