"""A model folder's ``model.json``: one typed definition that the engine reads and ``training.export`` writes.

The file holds ``format`` and ``version`` (:data:`MODEL_FORMAT`, :data:`MODEL_VERSION`) and the fields of
:class:`ModelConfig`, in the order of its fields (docs/engine.md, "Model files", lists them; a test checks that
table against this class). Fields left at None are not written; an unknown field is an error, so a file made for
another schema fails with its name instead of loading as something else.
"""

from __future__ import annotations

import dataclasses
import json
from dataclasses import dataclass
from typing import Any

from .host_kit.sky_map import NETWORK_SHAPE

__all__ = [
    "MAX_CARD_BLUR",
    "MODEL_FORMAT",
    "MODEL_VERSION",
    "ModelConfig",
    "ModelConfigError",
]

MODEL_FORMAT = "ssn-shadow-model"
MODEL_VERSION = 1
FRAME = 256  # the engine's frame size N: the shadow reach is in its pixels
MAX_CARD_BLUR = 4.0  # model pixels


class ModelConfigError(ValueError):
    """``model.json`` does not match the schema; the message names the field."""


@dataclass(frozen=True, kw_only=True)
class ModelConfig:
    """The fields of ``model.json`` (docs/engine.md, "Model files", says what each one means).

    Parameters
    ----------
    resolution
        R, the frame size the graphs run at (a multiple of 16).
    aop, sr, aop_camera, camera, surface, surface_second
        The graph files in the folder (``aop_camera``, ``camera``, ``surface``, ``surface_second``: optional;
        ``surface_second`` only beside ``surface``: a second surface graph, each pixel's height the higher of the
        two readings).
    elm_shape
        The network's light map shape, ``NETWORK_SHAPE``.
    output_floor, output_floor_small_lights
        Shadow values below these are removed (the second for one or two small lights; None: the first).
    shadow_reach
        Frame pixels (N = 256) from the card's shadow and the cutout beyond which small lights' shadows fade (0: off).
    ao_gamma
        The predicted AO map is raised to this power.
    card_blur
        Gaussian blur of the card's shadow in model pixels before the SR (0: off).
    mirror_average, card_input, sr_training, lights, training_data, camera_training, surface_training, export
        Informational records for people (the engine reads the graphs, not these).
    """

    aop: str = "aop.onnx"
    sr: str = "sr.onnx"
    aop_camera: str | None = None
    elm_shape: tuple[int, int] = NETWORK_SHAPE
    output_floor: float = 0.0
    mirror_average: bool = False
    output_floor_small_lights: float | None = None
    shadow_reach: float = 0.0
    ao_gamma: float = 1.0
    resolution: int
    card_input: bool | None = None
    sr_training: str | None = None
    card_blur: float = 0.0
    lights: str | None = None
    export: dict[str, Any] | None = None
    training_data: str | None = None
    camera: str | None = None
    camera_training: str | None = None
    surface: str | None = None
    surface_second: str | None = None
    surface_training: str | None = None

    def __post_init__(self) -> None:
        _check(self)

    @property
    def small_lights_floor(self) -> float:
        """The floor for one or two small lights: ``output_floor_small_lights``, else ``output_floor``."""
        return self.output_floor if self.output_floor_small_lights is None else self.output_floor_small_lights

    @classmethod
    def from_dict(cls, data: dict[str, Any]) -> ModelConfig:
        """The configuration of a parsed ``model.json``.

        Raises
        ------
        ModelConfigError
            The format or version is not this schema's, a field is unknown or missing, or a value is out of range.
        """
        if not isinstance(data, dict):
            raise ModelConfigError(f"expected a JSON object, got {type(data).__name__}")
        if data.get("format") != MODEL_FORMAT or data.get("version") != MODEL_VERSION:
            raise ModelConfigError(f"expected format {MODEL_FORMAT!r} version {MODEL_VERSION}")
        values = {k: v for k, v in data.items() if k not in ("format", "version")}
        unknown = sorted(set(values) - set(field_names()))
        if unknown:
            raise ModelConfigError(f"unknown field(s) {', '.join(map(repr, unknown))}")
        if "resolution" not in values:
            raise ModelConfigError("resolution must be a multiple of 16, got None")
        shape = values.get("elm_shape", NETWORK_SHAPE)
        if not isinstance(shape, (list, tuple)) or tuple(shape) != NETWORK_SHAPE:
            raise ModelConfigError(f"elm_shape must be {list(NETWORK_SHAPE)}")
        values["elm_shape"] = NETWORK_SHAPE
        return cls(**values)

    @classmethod
    def from_json(cls, text: str) -> ModelConfig:
        """The configuration in a ``model.json`` text (:meth:`from_dict`; invalid JSON: ModelConfigError)."""
        try:
            data = json.loads(text)
        except json.JSONDecodeError as exc:
            raise ModelConfigError(f"not JSON: {exc}") from None
        return cls.from_dict(data)

    def to_dict(self) -> dict[str, Any]:
        """``format``, ``version`` and every field that is not None, in the order of the fields."""
        out: dict[str, Any] = {"format": MODEL_FORMAT, "version": MODEL_VERSION}
        for f in dataclasses.fields(self):
            value = getattr(self, f.name)
            if value is not None:
                out[f.name] = list(value) if isinstance(value, tuple) else value
        return out

    def to_json(self) -> str:
        """The text of ``model.json`` (one-space indent, a final newline)."""
        return json.dumps(self.to_dict(), indent=1) + "\n"


def field_names() -> tuple[str, ...]:
    """The names of ``model.json``'s fields besides ``format`` and ``version``, in the file's order."""
    return tuple(f.name for f in dataclasses.fields(ModelConfig))


def _number(value: Any) -> bool:
    return isinstance(value, (int, float)) and not isinstance(value, bool)


def _check(config: ModelConfig) -> None:
    """Raise ModelConfigError naming the first field whose value the engine cannot use."""
    r = config.resolution
    if not isinstance(r, int) or isinstance(r, bool) or r < 16 or r % 16:
        raise ModelConfigError(f"resolution must be a multiple of 16, got {r!r}")
    for name, value in (
        ("output_floor", config.output_floor),
        ("output_floor_small_lights", config.small_lights_floor),
    ):
        if not _number(value) or not 0.0 <= value < 0.5:
            raise ModelConfigError(f"{name} must be a number in [0, 0.5), got {value!r}")
    if not _number(config.shadow_reach) or not 0.0 <= config.shadow_reach <= FRAME:
        raise ModelConfigError(f"shadow_reach must be a number of pixels in [0, {FRAME}], got {config.shadow_reach!r}")
    if not _number(config.ao_gamma) or not 0.1 <= config.ao_gamma <= 10.0:
        raise ModelConfigError(f"ao_gamma must be a number in [0.1, 10], got {config.ao_gamma!r}")
    if not _number(config.card_blur) or not 0.0 <= config.card_blur <= MAX_CARD_BLUR:
        raise ModelConfigError(
            f"card_blur must be a number of pixels in [0, {MAX_CARD_BLUR}], got {config.card_blur!r}"
        )
    optional = ("aop_camera", "camera", "surface", "surface_second")
    for name in ("aop", "sr", *optional):
        value = getattr(config, name)
        if not (value is None and name in optional) and (not isinstance(value, str) or not value):
            raise ModelConfigError(f"{name} must name a graph file, got {value!r}")
    if config.surface_second is not None and config.surface is None:
        raise ModelConfigError("surface_second needs surface: it is a second reading beside that graph's")
