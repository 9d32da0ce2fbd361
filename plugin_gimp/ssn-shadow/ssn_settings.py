"""The procedure's arguments and their validation (GIMP-free).

Every dialog setting is a procedure argument so that scripts and batch mode
can call the filter non-interactively. ``ARGUMENTS`` is the single list the
plug-in registers from; :class:`ShadowSettings` turns argument values into
engine requests.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

from ssn_engine_link import ao_edits, camera_rules, defaults, image_camera, light_map, protocol

PROCEDURE_NAME = "plug-in-ssn-shadow"
MENU_LABEL = "Soft _Shadow (SSN)..."
MENU_PATH = "<Image>/Filters/Light and Shadow"
IMAGE_TYPES = "RGB*, GRAY*"
LAYER_PREFIX = "Shadow: "
CLIP_MARGIN = 0.1  # share of the canvas's larger side a clipped shadow layer may reach past each edge
PRESET_LIST = ", ".join(light_map.PRESETS)  # every preset, from the host kit's table: none is left out
PROCEDURE_BLURB = "Soft shadow of a cutout (SSN)"
PROCEDURE_HELP = (
    "Adds a layer 'Shadow: <layer>' right below the layer: the soft shadow that the selection "
    "(or, with no selection, the layer's alpha) casts on the ground under the given light map, "
    "predicted by the ssn-shadow engine (SSN, CVPR 2021). The light map is a preset ("
    + PRESET_LIST
    + f"; default {light_map.DEFAULT_PRESET}) or light-map JSON. The layer is in Multiply mode; the "
    "layer and the selection are left as they are. One undo step removes it."
)


@dataclass(frozen=True)
class ArgSpec:
    """One procedure argument: ``kind`` is "string", "double", "boolean" or "color"."""

    name: str
    kind: str
    label: str
    blurb: str
    default: Any
    lo: float | None = None
    hi: float | None = None

    @property
    def bounds(self) -> tuple[float, float]:
        """(lo, hi) of a numeric argument."""
        if self.lo is None or self.hi is None:
            raise TypeError(f"{self.name} has no numeric range")
        return self.lo, self.hi


ARGUMENTS: tuple[ArgSpec, ...] = (
    ArgSpec(
        "light-map",
        "string",
        "_Light map",
        "A preset name (" + PRESET_LIST + ") or light-map JSON "
        '({"format": "ssn-shadow-elm", "version": 1, "lights": [...]})',
        light_map.DEFAULT_PRESET,
    ),
    ArgSpec("shadow-color", "color", "Shadow colo_ur", "Colour of the shadow (sRGB)", (0.0, 0.0, 0.0)),
    ArgSpec("opacity", "double", "O_pacity", "Shadow opacity, 0 (none) to 1 (full)", defaults.OPACITY, 0.0, 1.0),
    ArgSpec(
        "ao-strength",
        "double",
        "Contact shadow (_AO)",
        "Ambient-occlusion (contact shadow) strength: 0 removes it, 1 keeps the predicted one, up to 4",
        1.0,
        0.0,
        defaults.MAX_AO_STRENGTH,
    ),
    ArgSpec(
        "use-horizon",
        "boolean",
        "Set the image's _horizon",
        "Cast with the image's camera (horizon row and field of view); off: the camera read from the cutout's outline",
        False,
    ),
    ArgSpec(
        "horizon",
        "double",
        "Hori_zon row",
        "The image row (pixels from the top) where the ground meets the sky; it may lie outside the image",
        0.0,
        *camera_rules.EDITOR_HORIZON_RANGE,
    ),
    ArgSpec(
        "fov",
        "double",
        "_Field of view",
        "The image's vertical field of view in degrees",
        camera_rules.DEFAULT_FOV,
        *camera_rules.EDITOR_FOV_RANGE,
    ),
    ArgSpec(
        "keep-whole-shadow",
        "boolean",
        "_Keep the whole shadow",
        "Keep a long shadow whole, however far it reaches past the canvas; off: the layer ends a little past the "
        "canvas's edges (what can be seen when the layer is moved a bit)",
        False,
    ),
)
ARG_BY_NAME = {a.name: a for a in ARGUMENTS}


def image_camera_arguments(record: str | None, image_height: int) -> dict[str, Any]:
    """The camera arguments ("use-horizon", "horizon", "fov") an image's camera record gives it
    (:func:`image_camera.recalled_camera`; no record: the horizon not given), so that an image never takes
    another's."""
    camera = image_camera.recalled_camera(record, image_height)
    return {"use-horizon": camera["given"], "horizon": camera["horizon"], "fov": camera["fov"]}


def image_camera_record(values: dict[str, Any], image_height: int) -> str:
    """The camera record of an image from the camera arguments in ``values`` (:func:`image_camera.camera_record`)."""
    return image_camera.camera_record(values["use-horizon"], values["horizon"], values["fov"], image_height)


class SettingsError(ValueError):
    """A setting is out of range or malformed; the message names the argument."""


def resolve_light_map(text: str) -> dict[str, Any]:
    """Engine parameters for a light-map argument: ``{"preset": name}`` or ``{"light_map": {...}}``.

    Empty text means the default preset; text starting with ``{`` is parsed
    (and validated here, so errors name the field) as light-map JSON.
    """
    text = (text or "").strip()
    if not text:
        return {"preset": light_map.DEFAULT_PRESET}
    if text.startswith("{"):
        try:
            parsed = light_map.LightMap.from_json(text)
        except light_map.LightMapError as exc:
            raise SettingsError(f"light-map: {exc}") from None
        return {"light_map": parsed.to_dict()}
    if text in light_map.PRESETS:
        return {"preset": text}
    raise SettingsError(f"light-map: unknown preset {text!r}; give one of {PRESET_LIST} or light-map JSON")


def editor_light_map(text: str) -> light_map.LightMap:
    """The editable light map a light-map argument describes (for the dialog)."""
    params = resolve_light_map(text)
    if "preset" in params:
        return light_map.preset(params["preset"])
    return light_map.LightMap.from_dict(params["light_map"])


def _unit(value: Any, name: str, lo: float, hi: float) -> float:
    return protocol.checked_number(value, name, lo, hi, SettingsError)


@dataclass(frozen=True)
class ShadowSettings:
    """Validated settings of one shadow."""

    light_map: str = light_map.DEFAULT_PRESET
    color: tuple[float, float, float] = (0.0, 0.0, 0.0)
    opacity: float = defaults.OPACITY
    ao_strength: float = 1.0
    horizon: float | None = None  # the image's horizon row, or None: the engine's default camera
    fov: float = camera_rules.DEFAULT_FOV
    keep_whole: bool = False  # the layer keeps a long shadow whole, past the canvas plus its margin

    def __post_init__(self) -> None:
        if not isinstance(self.light_map, str):
            raise SettingsError(f"light-map: expected text, got {type(self.light_map).__name__}")
        if len(self.color) != 3:
            raise SettingsError(f"shadow-color: expected 3 components, got {len(self.color)}")
        color = tuple(_unit(c, "shadow-color", 0.0, 1.0) for c in self.color)
        object.__setattr__(self, "color", color)
        object.__setattr__(self, "opacity", _unit(self.opacity, "opacity", 0.0, 1.0))
        spec = ARG_BY_NAME["ao-strength"]
        object.__setattr__(self, "ao_strength", _unit(self.ao_strength, "ao-strength", *spec.bounds))
        if self.horizon is not None:
            spec = ARG_BY_NAME["horizon"]
            object.__setattr__(self, "horizon", _unit(self.horizon, "horizon", *spec.bounds))
        spec = ARG_BY_NAME["fov"]
        object.__setattr__(self, "fov", _unit(self.fov, "fov", *spec.bounds))
        resolve_light_map(self.light_map)  # validate now, before any pixel is read

    def camera(self) -> dict[str, float] | None:
        """The image's camera for ``set_cutout`` and ``set_camera`` (image rows), or None: the one the model reads."""
        return None if self.horizon is None else {"horizon": self.horizon, "fov": self.fov}

    def render_params(self, dtype: str, canvas: tuple[int, int]) -> dict[str, Any]:
        """Parameters of the worker's ``render`` command (without the cutout id) for a ``canvas`` (width,
        height): the layer clipped to the canvas grown by ``CLIP_MARGIN``, or the whole shadow."""
        clip = {"clip": False} if self.keep_whole else {"clip": True, "margin": round(CLIP_MARGIN * max(canvas))}
        return {
            **resolve_light_map(self.light_map),
            "color": list(self.color),
            "opacity": self.opacity,
            "format": {"dtype": dtype, "channels": "rgba"},
            **clip,
        }

    def ao_edits(self) -> list[dict[str, Any]]:
        """The AO edit list for ``edit_ao``; empty when the predicted AO is kept."""
        return ao_edits.strength_edits(self.ao_strength)
