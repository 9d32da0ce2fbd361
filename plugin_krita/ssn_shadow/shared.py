"""The host kit: the engine's stdlib-only modules, copied beside the plug-in, or ssn_engine in a checkout."""

from __future__ import annotations

from typing import TYPE_CHECKING

if TYPE_CHECKING:  # the copies are these modules
    from ssn_engine.host_kit import (
        ao_edits,
        camera_rules,
        client,
        defaults,
        engine_config,
        light_editor,
        light_map,
        light_map_picture,
        protocol,
        shadow_notes,
        sky_map,
    )
else:
    try:  # installed: the copy made by `ssn-shadow install-plugin`
        from .host_kit import (
            ao_edits,
            camera_rules,
            client,
            defaults,
            engine_config,
            light_editor,
            light_map,
            light_map_picture,
            protocol,
            shadow_notes,
            sky_map,
        )
    except ImportError:  # running from the repository (tests)
        from ssn_engine.host_kit import (
            ao_edits,
            camera_rules,
            client,
            defaults,
            engine_config,
            light_editor,
            light_map,
            light_map_picture,
            protocol,
            shadow_notes,
            sky_map,
        )

__all__ = [
    "ao_edits",
    "camera_rules",
    "client",
    "defaults",
    "engine_config",
    "light_editor",
    "light_map",
    "light_map_picture",
    "protocol",
    "shadow_notes",
    "sky_map",
]
