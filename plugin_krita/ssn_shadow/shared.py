"""The host kit's modules (``ssn_engine.host_kit``): the copy installed beside the plug-in, or the engine's own in a
checkout. ``from .shared import light_map`` reads the same in both."""

from __future__ import annotations

from typing import TYPE_CHECKING

if TYPE_CHECKING:  # the copy is this package
    from ssn_engine.host_kit import *  # noqa: F403
    from ssn_engine.host_kit import geometry_clamp, geometry_rules
else:
    try:  # installed: the copy made by `ssn-shadow install-plugin`
        from .host_kit import *  # noqa: F403
        from .host_kit import geometry_clamp, geometry_rules
    except ImportError:  # running from the repository (tests)
        from ssn_engine.host_kit import *  # noqa: F403
        from ssn_engine.host_kit import geometry_clamp, geometry_rules

__all__ = ["geometry_clamp", "geometry_rules"]  # besides the kit's own (its __all__)
