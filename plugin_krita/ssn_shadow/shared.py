"""The engine's toolkit-free modules: copies beside the plug-in, or ssn_engine in a checkout."""

from __future__ import annotations

try:  # installed: copies made by `ssn-shadow install-plugin krita`
    from .engine_shared import client, defaults, light_map, protocol
except ImportError:  # running from the repository (tests)
    from ssn_engine import client, defaults, light_map, protocol  # type: ignore[no-redef]

__all__ = ["client", "defaults", "light_map", "protocol"]
