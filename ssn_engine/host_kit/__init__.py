"""The host kit: what every front end (the Krita docker, the GIMP filter, the engine's CLI and worker) shares.

Standard library only: the plug-ins run in the host's own Python and carry a
copy of this package (:mod:`ssn_engine.plugin_files`). Each rule a host and
the engine must agree on is defined here once: the worker protocol and its
client, the light map, its editor and picture, a light's size in degrees, the camera rules, the AO edit
list, the shared defaults and wording.
"""

from __future__ import annotations

from . import (
    ao_edits,
    camera_rules,
    client,
    defaults,
    engine_config,
    engine_setup,
    image_camera,
    light_editor,
    light_map,
    light_map_picture,
    light_size,
    protocol,
    python_finder,
    setup_failures,
    shadow_notes,
    sky_map,
)

__all__ = [
    "ao_edits",
    "camera_rules",
    "client",
    "defaults",
    "engine_config",
    "engine_setup",
    "image_camera",
    "light_editor",
    "light_map",
    "light_map_picture",
    "light_size",
    "protocol",
    "python_finder",
    "setup_failures",
    "shadow_notes",
    "sky_map",
]
