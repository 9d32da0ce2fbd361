"""The docker's settings saved in the document, so that they travel with the .kra file.

Each document's :class:`model.ShadowModel` settings (light map, horizon,
colour, opacity, AO edits, lift and thickness) are written, as JSON, into one of the document's
annotations (:data:`ANNOTATION`) whenever the user changes one, and read
back when the docker first sees the document. Krita saves annotations in the
.kra file (``<name>/annotations/ssn_shadow/settings`` in the archive) and
loads them with it. Writing one changes no pixel and adds no undo step; it
marks the document modified, so closing it asks to save the changed settings.

The file format (version 1)::

    {"format": "ssn-shadow-krita-settings", "version": 1,
     "light_map": {...the light-map file's object...},
     "horizon": {"given": false, "row": 412.0, "fov": 45.0},
     "color": [0.0, 0.0, 0.0], "opacity": 0.85,
     "ao_edits": {"steps": [[{"op": "brush", ...}, ...], [{"op": "grow", "pixels": 2}]], "strength": 1.0},
     "geometry": {"lift": 40.0, "thickness": null},
     "shadows": {"<shadow layer's unique id>": {...the same six settings...}, ...}}

``geometry`` (optional: a file saved before it reads as resting on the ground, the thickness read) is the lift
in canvas rows and the thickness, ``null`` for the one read from the outline (conventions, "Lift and
thickness"); a reader that knows no ``geometry`` ignores it.

``shadows`` (optional) records the settings each shadow layer was rendered
from, so that an undo that brings back an older shadow layer brings back its
light map and the rest (:meth:`model.ShadowModel.shadow_shown`); Krita keeps
a layer's unique id in the .kra. A record that cannot be read is dropped
(the rest is read).
"""

from __future__ import annotations

import json
import math
from typing import Any

from .model import Settings, ShadowModel
from .shared import ao_edits, camera_rules, defaults, geometry_rules, protocol
from .shared import light_map as lm

__all__ = ["ANNOTATION", "DocumentModels", "SettingsError", "dump", "restore"]

ANNOTATION = "ssn_shadow/settings"  # the annotation's type (its name in the document)
DESCRIPTION = "Soft Shadow docker settings (ssn-shadow)"
FORMAT = "ssn-shadow-krita-settings"
VERSION = 1
AO_OPS = ("brush", "grow")


class SettingsError(ValueError):
    """Saved settings that cannot be read; the message names the field."""


def dump(model: ShadowModel) -> bytes:
    """The model's settings (and its shadow layers' records) as the annotation's bytes (UTF-8 JSON)."""
    data = {"format": FORMAT, "version": VERSION, **_settings_dict(model.settings())}
    if model.shadows:
        data["shadows"] = {layer: _settings_dict(settings) for layer, settings in model.shadows.items()}
    return json.dumps(data, separators=(",", ":")).encode("utf-8")


def restore(model: ShadowModel, data: bytes) -> None:
    """Set ``model``'s settings from the annotation's bytes: all of them, or (on :class:`SettingsError`) none.
    The widgets show them; it is no edit (nothing is rendered or saved)."""
    try:
        settings = protocol.loads(data)
    except (UnicodeDecodeError, ValueError) as exc:  # not JSON, or nested past what a reader takes
        raise SettingsError(f"not JSON ({exc})") from None
    protocol.versioned(settings, FORMAT, VERSION, "this Soft Shadow", SettingsError)
    current = _settings(settings)
    shadows = settings.get("shadows", {})
    if not isinstance(shadows, dict):
        raise SettingsError(f"shadows: expected an object, got {shadows!r}")
    records = {}
    for layer, record in shadows.items():
        try:
            records[str(layer)] = _settings(record if isinstance(record, dict) else {})
        except SettingsError:
            continue  # that layer's settings are lost; its shadow stays as it is
    model.apply(current)
    model.shadows = records


def _settings_dict(s: Settings) -> dict[str, Any]:
    return {
        "light_map": s.light_map.to_dict(),
        "horizon": {"given": s.use_horizon, "row": s.horizon, "fov": s.fov},
        "color": list(s.color),
        "opacity": s.opacity,
        "ao_edits": {"steps": s.ao_edits.steps, "strength": s.ao_strength},
        "geometry": {"lift": s.lift, "thickness": s.thickness},
    }


def _settings(settings: dict) -> Settings:
    try:
        light_map = lm.LightMap.from_dict(settings.get("light_map"))
    except lm.LightMapError as exc:
        raise SettingsError(f"light_map: {exc}") from None
    horizon = _object(settings, "horizon")
    given = horizon.get("given")
    if not isinstance(given, bool):
        raise SettingsError(f"horizon.given: expected true or false, got {given!r}")
    row = _number(horizon.get("row"), "horizon.row", *camera_rules.EDITOR_HORIZON_RANGE)
    fov = _number(horizon.get("fov"), "horizon.fov", *camera_rules.EDITOR_FOV_RANGE)
    color = settings.get("color")
    if not isinstance(color, list) or len(color) != 3:
        raise SettingsError(f"color: expected [red, green, blue], got {color!r}")
    rgb = (
        _number(color[0], "color[0]", 0.0, 1.0),
        _number(color[1], "color[1]", 0.0, 1.0),
        _number(color[2], "color[2]", 0.0, 1.0),
    )
    opacity = _number(settings.get("opacity"), "opacity", 0.0, 1.0)
    ao = _object(settings, "ao_edits")
    steps = _ao_steps(ao.get("steps"))
    strength = _number(ao.get("strength"), "ao_edits.strength", 0.0, defaults.MAX_AO_STRENGTH)
    geometry = _object(settings, "geometry") if "geometry" in settings else {}
    lift = _number(geometry.get("lift", 0.0), "geometry.lift", 0.0, math.inf)  # clamped to its canvas when rendered
    thickness = geometry.get("thickness")
    if thickness is not None:
        thickness = _number(thickness, "geometry.thickness", *geometry_rules.THICKNESS_RANGE)
    return Settings(light_map, given, row, fov, rgb, opacity, ao_edits.AoEdits(steps), strength, lift, thickness)


def _object(settings: dict, key: str) -> dict:
    value = settings.get(key)
    if not isinstance(value, dict):
        raise SettingsError(f"{key}: expected an object, got {value!r}")
    return value


def _number(value: Any, where: str, lo: float, hi: float) -> float:
    return protocol.checked_number(value, where, lo, hi, SettingsError)


def _ao_steps(steps: Any) -> list[list[dict]]:
    """The steps' structure (the engine checks each op's numbers when it applies them)."""
    if not isinstance(steps, list):
        raise SettingsError(f"ao_edits.steps: expected a list, got {steps!r}")
    for i, step in enumerate(steps):
        if not isinstance(step, list) or not step:
            raise SettingsError(f"ao_edits.steps[{i}]: expected a non-empty list of edits")
        for j, op in enumerate(step):
            if not isinstance(op, dict) or op.get("op") not in AO_OPS:
                raise SettingsError(f"ao_edits.steps[{i}][{j}]: expected a 'brush' or 'grow' edit, got {op!r}")
    return steps


class DocumentModels:
    """A :class:`ShadowModel` per open document, loaded from the document's annotation when first asked for,
    and saved into it at each change of a setting.

    ``host`` reads and writes annotations (:class:`adapters.host.KritaHost`): the only document access.
    """

    def __init__(self, host: Any) -> None:
        self.host = host
        self._models: list[tuple[Any, ShadowModel]] = []

    def is_closed(self, model: ShadowModel) -> bool:
        """Whether ``model`` is the model of a document that is no longer open (a model of no document, or one
        this object did not make: False)."""
        return any(known is model and not self.host.is_open(document) for document, known in self._models)

    def model_for(self, document: Any) -> ShadowModel:
        """The model of ``document`` (None: a model of its own, saved nowhere)."""
        if document is None:
            return ShadowModel()
        self._models = [(d, m) for d, m in self._models if self.host.is_open(d)]  # forget closed documents
        for known, model in self._models:
            if known == document:
                return model
        model = ShadowModel()
        data = self.host.annotation(document, ANNOTATION)
        if data:
            try:
                restore(model, data)
            except SettingsError as exc:  # shown; the saved settings stay until a setting is changed
                model.report_status(
                    "warning",
                    f"The Soft Shadow settings saved in this image cannot be read ({exc}); the docker starts from "
                    "its defaults, and the image keeps the saved ones until a setting is changed.",
                )
        model.modified.connect(lambda _name: self.host.set_annotation(document, ANNOTATION, DESCRIPTION, dump(model)))
        self._models.append((document, model))
        return model
