"""Why a shadow shows nothing, in the words every front end uses (stdlib only).

The worker says why in a reply's ``no_shadow`` (``render``, ``preview``); the CLI prints the same reasons; a
host shows :func:`no_shadow_note` of it.
"""

from __future__ import annotations

__all__ = ["HIDDEN", "NO_LIGHT", "no_shadow_note"]

NO_LIGHT = "the light map has no light (no lights, or all at intensity 0)"
HIDDEN = "this light casts no shadow visible in the image (it falls behind the cutout)"


def no_shadow_note(reason: str | None) -> str:
    """The sentence a host shows for a reply's ``no_shadow`` reason (None: the reply gave none)."""
    return f"No visible shadow: {reason or 'these lights cast none inside the image'}."
