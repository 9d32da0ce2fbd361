"""Where the GIMP plug-in finds the engine: the host kit's modules and the worker they reach.

The installed plug-in carries copies of the engine's stdlib-only modules in
``host_kit/`` (the host kit: protocol, client, engine config, light map
and its editor, defaults, the lift and thickness rules and clamps) and the ``engine.json`` that ``ssn-shadow
install-plugin gimp`` wrote; in a source checkout (tests) the modules come
from ``ssn_engine`` itself. GIMP-free.
"""

from __future__ import annotations

from pathlib import Path
from typing import TYPE_CHECKING

if TYPE_CHECKING:  # the copy is this package
    from ssn_engine.host_kit import *  # noqa: F403
    from ssn_engine.host_kit import client, engine_config, engine_setup, geometry_clamp, geometry_rules  # noqa: F401
else:
    try:  # installed: the copy made by `ssn-shadow install-plugin`
        from host_kit import *  # noqa: F403
        from host_kit import client, engine_config, engine_setup, geometry_clamp, geometry_rules  # noqa: F401
    except ImportError:  # running from the repository (tests)
        from ssn_engine.host_kit import *  # noqa: F403
        from ssn_engine.host_kit import client, engine_config, engine_setup, geometry_clamp, geometry_rules  # noqa: F401

PLUGIN_DIR = Path(__file__).resolve().parent
WORKER_STATE = "worker.json"  # the shared worker's address and token (this user only)


def connect(
    timeout: float = 120.0, plugin_dir: Path = PLUGIN_DIR, on_wait: client.OnWait | None = None
) -> client.EngineClient:
    """A client of the engine configured for this plug-in (:func:`engine_config.load_engine_config`). A command
    configuration reuses one worker across filter calls (recorded in ``worker.json`` beside the plug-in; it exits
    after 15 idle minutes) unless it says ``"shared": false``. ``on_wait`` is asked while a reply is awaited
    whether the user has given up (:class:`client.EngineClient`)."""
    config = engine_config.load_engine_config(plugin_dir, "gimp")
    return client.connect(config, Path(plugin_dir) / WORKER_STATE, timeout, on_wait)
