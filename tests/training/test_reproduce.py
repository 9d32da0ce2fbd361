"""training/reproduce.sh, the shipped model's recipe: every command it runs parses, and its export asks for the
settings the shipped model.json holds."""

from __future__ import annotations

import importlib
import os
import shlex
import subprocess
from pathlib import Path

import pytest

from ssn_engine.model_config import ModelConfig

pytest.importorskip("torch")

ROOT = Path(__file__).resolve().parents[2]
SCRIPT = ROOT / "training" / "reproduce.sh"


def _commands(tmp_path: Path) -> list[tuple[str, list[str]]]:
    """(module, arguments) of every command the script runs, from a dry run."""
    out = subprocess.run(
        ["bash", str(SCRIPT), str(tmp_path / "data"), str(tmp_path / "runs"), str(tmp_path / "model")],
        env={**os.environ, "DRY_RUN": "1"},
        capture_output=True,
        text=True,
        check=True,
        cwd=ROOT,
    ).stdout
    commands = []
    for line in out.splitlines():
        words = shlex.split(line)
        assert words[:3] == ["+", "python", "-m"], line
        commands.append((words[3], words[4:]))
    return commands


def test_every_command_of_the_recipe_parses(tmp_path):
    commands = _commands(tmp_path)
    modules = [m for m, _ in commands]
    for stage in ("make_dataset", "train", "heights", "camera_estimator", "export"):
        assert f"training.{stage}" in modules
    assert not (tmp_path / "data").exists() and not (tmp_path / "runs").exists()  # a dry run writes nothing
    for module, argv in commands:
        importlib.import_module(module).parse_args(argv)  # argparse exits on an unknown or malformed option


def test_the_recipes_export_makes_the_shipped_settings(tmp_path):
    shipped = ModelConfig.from_json((ROOT / "ssn_engine" / "models" / "model.json").read_text())
    final = [argv for module, argv in _commands(tmp_path) if module == "training.export"][-1]
    args = importlib.import_module("training.export").parse_args(final)
    assert args.out == str(tmp_path / "model") and args.aop_camera and args.mirror_average
    assert (args.floor, args.floor_small_lights) == (shipped.output_floor, shipped.output_floor_small_lights)
    assert (args.shadow_reach, args.ao_gamma) == (shipped.shadow_reach, shipped.ao_gamma)
    train = importlib.import_module("training.train")
    sr = [train.parse_args(a) for m, a in _commands(tmp_path) if m == "training.train" and "sr_zncc2" in " ".join(a)]
    assert sr[0].card_blur == shipped.card_blur and sr[0].lights == "mix"
