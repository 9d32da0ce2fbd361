"""The host kit: the engine's stdlib-only modules, copied beside the plug-in, or ssn_engine in a checkout."""

from __future__ import annotations

from typing import TYPE_CHECKING

if TYPE_CHECKING:  # the copies are these modules
    from ssn_engine.host_kit import (
        client,
        defaults,
        engine_config,
        light_editor,
        light_map,
        light_map_picture,
        protocol,
    )
else:
    try:  # installed: copies made by `ssn-shadow install-plugin krita`
        from .host_kit import client, defaults, engine_config, light_editor, light_map, light_map_picture, protocol
    except ImportError:  # running from the repository (tests)
        from ssn_engine.host_kit import (
            client,
            defaults,
            engine_config,
            light_editor,
            light_map,
            light_map_picture,
            protocol,
        )

__all__ = ["client", "defaults", "engine_config", "light_editor", "light_map", "light_map_picture", "protocol"]
