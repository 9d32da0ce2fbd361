"""How a plug-in reaches the engine worker (stdlib only; both plug-ins carry a copy).

In order: ``$SSN_SHADOW_ENGINE_ADDRESS`` (``TOKEN@host:port`` of a running
``ssn-shadow serve --port``), ``$SSN_SHADOW_ENGINE_CONFIG`` (the path of an
``engine.json``), the ``engine.json`` that ``ssn-shadow install-plugin`` wrote
beside the plug-in; for a packaged plug-in (``ssn-shadow package``, its
``setup.json`` beside it) the environment its Set up made
(:mod:`engine_setup`), else :class:`EngineSetupNeeded`; last ``ssn-shadow``
found on PATH.

``engine.json`` either names the Python that runs the worker
(``{"python": ..., "args": [...], "env": {...}, "shared": true}``) or the
loopback address of a running worker and the token it printed when it started
(``{"address": ["127.0.0.1", port], "token": "..."}``).
"""

from __future__ import annotations

import json
import os
import shutil
from collections.abc import Mapping
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

from . import engine_setup

CONFIG_NAME = "engine.json"
CONFIG_ENV = "SSN_SHADOW_ENGINE_CONFIG"
ADDRESS_ENV = "SSN_SHADOW_ENGINE_ADDRESS"
DEFAULT_ARGS = ("-m", "ssn_engine", "serve")


class EngineConfigError(RuntimeError):
    """The engine cannot be found or its configuration is malformed; the message says what to do."""


class EngineSetupNeeded(EngineConfigError):
    """A packaged plug-in whose engine is not set up (or set up for an older plug-in): the host offers Set up."""

    def __init__(self, message: str, bundle: engine_setup.Bundle, state: engine_setup.State) -> None:
        super().__init__(message)
        self.bundle, self.state = bundle, state


@dataclass(frozen=True)
class EngineConfig:
    """Either the ``command`` that starts ``ssn-shadow serve`` or the ``address`` of a running worker."""

    command: tuple[str, ...] = ()
    address: tuple[str, int] | None = None
    token: str = ""
    env: Mapping[str, str] = field(default_factory=dict)  # added to the worker's environment
    shared: bool = True  # a command's worker outlives a call (plug-ins that run once per call)
    source: str = ""  # where this came from, for messages

    def describe(self) -> str:
        if self.address is not None:
            return f"the worker at {self.address[0]}:{self.address[1]}"
        return " ".join(self.command)


def parse_address(text: str) -> tuple[str, int, str]:
    """Parse ``[TOKEN@]host:port`` into a socket address and the worker's token ("" if none)."""
    token, _, address = text.strip().rpartition("@")
    host, sep, port = address.rpartition(":")
    if not sep or not host or not port.isdigit() or not 0 < int(port) < 65536:
        raise EngineConfigError(f"expected an engine address as TOKEN@host:port, got {text!r}")
    return host, int(port), token


def read_config(path: Path, host: str) -> EngineConfig:
    """Parse one ``engine.json``; errors name the field and say how to repair it."""
    again = f"Re-run 'ssn-shadow install-plugin {host}'."
    try:
        data = json.loads(path.read_text(encoding="utf-8"))
    except FileNotFoundError:
        raise EngineConfigError(f"The shadow engine is not configured ({path} is missing). {again}") from None
    except (OSError, ValueError) as exc:
        raise EngineConfigError(f"Cannot read {path}: {exc}. {again}") from None
    if not isinstance(data, dict):
        raise EngineConfigError(f"{path}: expected a JSON object. {again}")
    if "address" in data:
        return _address_config(data, path)
    return _command_config(data, path)


def _address_config(data: dict[str, Any], path: Path) -> EngineConfig:
    address = data["address"]
    if (
        not isinstance(address, list)
        or len(address) != 2
        or not isinstance(address[0], str)
        or not isinstance(address[1], int)
    ):
        raise EngineConfigError(f'{path}: "address" must be ["host", port], got {address!r}')
    token = data.get("token", "")
    if not isinstance(token, str):
        raise EngineConfigError(f'{path}: "token" must be the string the worker printed when it started')
    return EngineConfig(address=(address[0], address[1]), token=token, source=str(path))


def _command_config(data: dict[str, Any], path: Path) -> EngineConfig:
    python, args = data.get("python"), data.get("args", list(DEFAULT_ARGS))
    env, shared = data.get("env", {}), data.get("shared", True)
    if not isinstance(python, str) or not python:
        raise EngineConfigError(f'{path}: "python" must name the Python that has ssn-shadow installed')
    if not isinstance(args, list) or not all(isinstance(a, str) for a in args):
        raise EngineConfigError(f'{path}: "args" must be a list of strings')
    if not isinstance(env, dict) or not all(isinstance(k, str) and isinstance(v, str) for k, v in env.items()):
        raise EngineConfigError(f'{path}: "env" must map names to strings')
    if not isinstance(shared, bool):
        raise EngineConfigError(f'{path}: "shared" must be true or false')
    return EngineConfig(command=(python, *args), env=dict(env), shared=shared, source=str(path))


def load_engine_config(plugin_dir: Path, host: str) -> EngineConfig:
    """The engine for the plug-in in ``plugin_dir`` (``host``: "krita" or "gimp", for messages)."""
    address = os.environ.get(ADDRESS_ENV)
    if address:
        name, port, token = parse_address(address)
        return EngineConfig(address=(name, port), token=token, source=ADDRESS_ENV)
    override = os.environ.get(CONFIG_ENV)
    if override:
        return read_config(Path(override), host)
    local = Path(plugin_dir) / CONFIG_NAME
    if local.is_file():
        return read_config(local, host)
    try:
        bundle = engine_setup.read_bundle(Path(plugin_dir))
    except engine_setup.SetupError as exc:
        raise EngineConfigError(str(exc)) from None
    if bundle is not None:
        state = engine_setup.engine_state(bundle, engine_setup.data_dir())
        if state.status != "ready":
            raise EngineSetupNeeded(state.describe(bundle), bundle, state)
        # its own environment: none of the host's Python paths (an embedded Python's PYTHONPATH) may leak in
        command = (str(state.python), *DEFAULT_ARGS)
        return EngineConfig(command=command, env={"PYTHONPATH": ""}, source=str(state.python))
    exe = shutil.which("ssn-shadow")
    if exe:
        return EngineConfig(command=(exe, "serve"), source="PATH")
    raise EngineConfigError(
        "The shadow engine is not configured: install ssn-shadow in a Python environment (pip install ssn-shadow) "
        f"and run 'ssn-shadow install-plugin {host}' from it."
    )


def worker_environment(base: Mapping[str, str], extra: Mapping[str, str]) -> dict[str, str]:
    """The worker's environment: the host's, minus the host's own Python settings, plus ``extra``."""
    env = {k: v for k, v in base.items() if k not in ("PYTHONHOME", "PYTHONSTARTUP", "PYTHONEXECUTABLE")}
    env.update(extra)
    env.setdefault("PYTHONUNBUFFERED", "1")
    return env
