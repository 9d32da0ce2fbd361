"""Where the engine worker comes from: engine.json beside the plug-in, or ssn-shadow on PATH."""

from __future__ import annotations

import json
import os
import shutil
from dataclasses import dataclass, field
from pathlib import Path

CONFIG_ENV = "SSN_SHADOW_ENGINE_CONFIG"
CONFIG_NAME = "engine.json"
PLUGIN_DIR = Path(__file__).resolve().parent


class EngineConfigError(RuntimeError):
    """The engine command cannot be worked out; the message says what to do."""


@dataclass(frozen=True)
class EngineCommand:
    """The program and arguments that start ``ssn-shadow serve``, plus extra environment."""

    program: str
    args: list[str]
    env: dict[str, str] = field(default_factory=dict)
    source: str = ""

    def describe(self) -> str:
        return " ".join([self.program, *self.args])


def _from_file(path: Path) -> EngineCommand:
    try:
        data = json.loads(path.read_text(encoding="utf-8"))
    except (OSError, json.JSONDecodeError) as exc:
        raise EngineConfigError(f"cannot read the engine configuration {path}: {exc}") from None
    python = data.get("python") if isinstance(data, dict) else None
    args = data.get("args", ["-m", "ssn_engine", "serve"]) if isinstance(data, dict) else None
    env = data.get("env", {}) if isinstance(data, dict) else {}
    if not isinstance(python, str) or not isinstance(args, list) or not isinstance(env, dict):
        raise EngineConfigError(
            f"{path} is not a valid engine configuration (expected 'python' and 'args'); "
            "re-run 'ssn-shadow install-plugin krita'."
        )
    return EngineCommand(python, [str(a) for a in args], {str(k): str(v) for k, v in env.items()}, str(path))


def engine_command(plugin_dir: Path = PLUGIN_DIR) -> EngineCommand:
    """The worker command: $SSN_SHADOW_ENGINE_CONFIG, else engine.json beside the plug-in,
    else ``ssn-shadow serve`` found on PATH."""
    override = os.environ.get(CONFIG_ENV)
    if override:
        return _from_file(Path(override))
    local = plugin_dir / CONFIG_NAME
    if local.is_file():
        return _from_file(local)
    exe = shutil.which("ssn-shadow")
    if exe:
        return EngineCommand(exe, ["serve"], source="PATH")
    raise EngineConfigError(
        "The shadow engine is not configured: install ssn-shadow in a Python environment "
        "(pip install ssn-shadow) and run 'ssn-shadow install-plugin krita' from it."
    )


def worker_environment(base: dict[str, str], extra: dict[str, str]) -> dict[str, str]:
    """The worker's environment: the host's, minus the host's own Python home, plus ``extra``."""
    env = {k: v for k, v in base.items() if k not in ("PYTHONHOME", "PYTHONSTARTUP", "PYTHONEXECUTABLE")}
    env.update(extra)
    env.setdefault("PYTHONUNBUFFERED", "1")
    return env
