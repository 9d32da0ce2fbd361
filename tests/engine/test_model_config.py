"""model.json's one definition: the shipped file round-trips byte for byte, bad values are named, and the docs'
table lists exactly its fields."""

from __future__ import annotations

import dataclasses
import json
import re
from pathlib import Path

import pytest

from ssn_engine.model_config import ModelConfig, ModelConfigError, field_names

ROOT = Path(__file__).resolve().parents[2]
SHIPPED = ROOT / "ssn_engine" / "models" / "model.json"


def test_the_shipped_model_json_is_rewritten_byte_for_byte():
    text = SHIPPED.read_text()
    config = ModelConfig.from_json(text)
    assert config.to_json() == text
    assert config.resolution == 128 and config.aop_camera == "aop_camera.onnx" and config.card_blur == 1.2


def test_unset_fields_are_not_written_and_the_small_light_floor_defaults_to_the_floor():
    config = ModelConfig(resolution=64, output_floor=0.01)
    data = json.loads(config.to_json())
    assert "aop_camera" not in data and "camera" not in data and "output_floor_small_lights" not in data
    assert data["format"] == "ssn-shadow-model" and data["elm_shape"] == [16, 32]
    assert config.small_lights_floor == 0.01
    assert ModelConfig.from_json(config.to_json()) == config


@pytest.mark.parametrize(
    "change, fragment",
    [
        ({"height": "height.onnx"}, "'height'"),
        ({"resolution": 100}, "resolution"),
        ({"version": 2}, "version"),
        ({"elm_shape": [8, 16]}, "elm_shape"),
        ({"shadow_reach": "16"}, "shadow_reach"),
        ({"aop": ""}, "aop"),
        ({"camera": 3}, "camera"),
        ({"surface": None, "surface_second": "surface_second.onnx"}, "surface_second needs surface"),
    ],
)
def test_a_bad_field_is_named(change, fragment):
    data = {**json.loads(SHIPPED.read_text()), **change}
    with pytest.raises(ModelConfigError, match=fragment):
        ModelConfig.from_dict(data)


def test_a_config_is_immutable():
    config = ModelConfig(resolution=128)
    with pytest.raises(dataclasses.FrozenInstanceError):
        config.resolution = 64  # type: ignore[misc]


def test_the_docs_table_lists_exactly_the_fields():
    text = (ROOT / "docs" / "engine.md").read_text()
    section = text[text.index("## Model files") :]
    section = section[: section.index("\n## ", 1)]
    rows = [line for line in section.splitlines() if line.startswith("| `")]
    documented = [name for row in rows for name in re.findall(r"`(\w+)`", row.split(" | ")[0])]
    assert sorted(documented) == sorted(("format", "version") + field_names())
