"""Which of the docker's sections are open for a given dock height (pure Python: no Qt, no Krita).

The panel shows the light editor (the sky map, the preset, Size and Intensity) first and the rest in sections
that fold: the preview, the ambient occlusion, the camera, the object's geometry (lift and thickness) and the
shadow's colour and opacity. In a short dock
(Krita's default workspace on a 1366 x 768 screen gives a docker stacked under the others about 180 px tall) the
sections start folded, so that the map and Generate are in view without scrolling; in a taller one they start
open. A section the artist folded or unfolded stays so (the panel remembers the choice).
"""

from __future__ import annotations

from collections.abc import Mapping

SECTIONS = ("preview", "ao", "camera", "geometry", "shadow")  # below the light editor, top to bottom
TITLES = {
    "preview": "Preview",
    "ao": "Ambient occlusion",
    "camera": "Camera",
    "geometry": "Geometry",
    "shadow": "Shadow",
}
SHORT_PANEL = 480  # pixels: a panel shorter than this starts with its sections folded
MAP_MIN_HEIGHT = 72  # pixels: the sky map never gets shorter (the scroll area keeps room for it in any dock)


def open_sections(panel_height: int, chosen: Mapping[str, bool]) -> dict[str, bool]:
    """Each section's state (True: open) in a panel ``panel_height`` pixels tall: the artist's choice where
    ``chosen`` has one, else open unless the panel is shorter than ``SHORT_PANEL``."""
    default = panel_height >= SHORT_PANEL
    return {name: bool(chosen.get(name, default)) for name in SECTIONS}


def map_height_cap(viewport_height: int, margins: int) -> int:
    """The sky map's greatest height in a scroll viewport ``viewport_height`` pixels tall whose content has
    ``margins`` pixels above and below it: all of the map fits in view at the top (it is drawn 2:1 within its
    box, narrower where the box is wide), but never shorter than ``MAP_MIN_HEIGHT``."""
    return max(MAP_MIN_HEIGHT, viewport_height - margins)
