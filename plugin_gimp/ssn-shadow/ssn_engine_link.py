"""Where the plug-in finds the engine: its shared modules and its worker.

The installed plug-in carries copies of ``light_map``, ``protocol`` and
``client`` in ``engine_shared/`` and an ``engine.json`` that either names the
Python that runs ``python -m ssn_engine serve`` (``{"python", "args"}``; the
worker it starts outlives the call unless ``"shared": false``) or the
loopback address of a running worker and the token it printed when it started
(``{"address": ["127.0.0.1", port], "token": "..."}``).
In a source checkout (tests) the modules come from ``ssn_engine`` itself.
GIMP-free and stdlib-only.
"""

from __future__ import annotations

import json
import os
from pathlib import Path
from typing import Any

try:  # installed plug-in
    from engine_shared import client, defaults, light_map, protocol  # type: ignore[import-not-found]
except ImportError:  # source checkout
    from ssn_engine import client, defaults, light_map, protocol  # type: ignore[no-redef]

__all__ = ["client", "defaults", "light_map", "protocol", "EngineConfigError", "load_engine_config", "connect"]

PLUGIN_DIR = Path(__file__).resolve().parent
CONFIG_NAME = "engine.json"
ADDRESS_ENV = "SSN_SHADOW_ENGINE_ADDRESS"
WORKER_STATE = "worker.json"  # the shared worker's address and token (this user only)


class EngineConfigError(RuntimeError):
    """engine.json is missing or malformed; the message tells the user what to do."""


def parse_address(text: str) -> tuple[str, int, str]:
    """Parse ``[TOKEN@]host:port`` (IPv4 or a name) into a socket address and the worker's token ("" if none)."""
    token, _, address = text.strip().rpartition("@")
    host, sep, port = address.rpartition(":")
    if not sep or not host or not port.isdigit() or not 0 < int(port) < 65536:
        raise EngineConfigError(f"expected an engine address as TOKEN@host:port, got {text!r}")
    return host, int(port), token


def load_engine_config(plugin_dir: Path | None = None) -> dict[str, Any]:
    """Read ``engine.json``; the environment variable SSN_SHADOW_ENGINE_ADDRESS (``TOKEN@host:port``)
    overrides it."""
    override = os.environ.get(ADDRESS_ENV)
    if override:
        host, port, token = parse_address(override)
        return {"address": [host, port], "token": token}
    path = Path(plugin_dir or PLUGIN_DIR) / CONFIG_NAME
    try:
        config = json.loads(path.read_text(encoding="utf-8"))
    except FileNotFoundError:
        raise EngineConfigError(
            f"The shadow engine is not configured ({path} is missing). "
            "Install the plug-in with 'ssn-shadow install-plugin gimp'."
        ) from None
    except (OSError, ValueError) as exc:
        raise EngineConfigError(f"Cannot read {path}: {exc}. Re-run 'ssn-shadow install-plugin gimp'.") from None
    if not isinstance(config, dict):
        raise EngineConfigError(f"{path}: expected a JSON object")
    if "address" in config:
        address = config["address"]
        if (
            not isinstance(address, list)
            or len(address) != 2
            or not isinstance(address[0], str)
            or not isinstance(address[1], int)
        ):
            raise EngineConfigError(f'{path}: "address" must be ["host", port], got {address!r}')
        token = config.get("token", "")
        if not isinstance(token, str):
            raise EngineConfigError(f'{path}: "token" must be the string the worker printed when it started')
        return {"address": [address[0], address[1]], "token": token}
    python, args = config.get("python"), config.get("args", ["-m", "ssn_engine", "serve"])
    if not isinstance(python, str) or not python:
        raise EngineConfigError(f'{path}: "python" must name the Python that has ssn-shadow installed')
    if not isinstance(args, list) or not all(isinstance(a, str) for a in args):
        raise EngineConfigError(f'{path}: "args" must be a list of strings')
    shared = config.get("shared", True)
    if not isinstance(shared, bool):
        raise EngineConfigError(f'{path}: "shared" must be true or false')
    return {"command": [python, *args], "shared": shared}


def connect(config: dict[str, Any], timeout: float = 120.0, plugin_dir: Path | None = None) -> client.EngineClient:
    """An engine client for a config from :func:`load_engine_config`. A command config with ``shared`` (the
    default) reuses one worker across filter calls (``client.shared_client``, recorded in ``worker.json`` beside
    the plug-in; it exits after 15 idle minutes); without it, each call spawns its own (connects lazily)."""
    if "address" in config:
        host, port = config["address"]
        return client.EngineClient(address=(host, int(port)), timeout=timeout, token=config.get("token"))
    if config.get("shared"):
        return client.shared_client(config["command"], Path(plugin_dir or PLUGIN_DIR) / WORKER_STATE, timeout)
    return client.EngineClient(command=list(config["command"]), timeout=timeout)
