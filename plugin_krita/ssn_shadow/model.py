"""The docker's state for one document: its shadow settings, and what the docker shows about it.

One :class:`ShadowModel` per open document (:class:`persistence.DocumentModels`
keeps them). The panel binds its widgets to the model's properties; the
controller renders what the model says and reports back into it (status,
the camera the engine read). The settings (light map, horizon, colour,
opacity, AO edits) are saved in the document (:mod:`persistence`).

Signals besides each property's ``<name>_changed``:

- ``modified(name)``: a setting saved with the document changed (by a user edit), or ``"shadows"``: the
  record of which settings made which shadow layer changed;
- ``edited(what, new_step)``: a user edit the shadow depends on, ``what`` one of :data:`EDITS`;
  ``new_step``: the shadow layer's write starts a new undo step (the first change of a slider drag, a
  click) or continues the current one (the rest of the drag).
"""

from __future__ import annotations

from collections.abc import Iterator
from contextlib import contextmanager
from dataclasses import dataclass

from PyQt5.QtCore import QObject, pyqtSignal

from .properties import Property
from .shared import ao_edits, camera_rules, defaults
from .shared import light_map as lm

AoEdits = ao_edits.AoEdits  # the kit's AO edit list (a model property shares the module's name)

__all__ = ["EDITS", "MAX_SHADOW_RECORDS", "READY", "Settings", "ShadowModel"]

MAX_SHADOW_RECORDS = 32  # shadow layers whose settings are kept (the newest; older undo steps forget theirs)
READY = "Select the cutout's layer (or a selection) and press Generate."
EDITS = ("light_map", "camera", "color", "opacity", "ao_edits")
_CAMERA = ("use_horizon", "horizon", "fov")


@dataclass(frozen=True)
class Settings:
    """The settings a shadow is rendered from (a snapshot: its light map and AO edits are copies)."""

    light_map: lm.LightMap
    use_horizon: bool
    horizon: float
    fov: float
    color: tuple[float, float, float]
    opacity: float
    ao_edits: AoEdits
    ao_strength: float


class ShadowModel(QObject):
    """One document's shadow settings (editable) and the docker's derived state about it (read-only)."""

    light_map_changed = pyqtSignal(object)
    use_horizon_changed = pyqtSignal(bool)
    horizon_changed = pyqtSignal(float)
    fov_changed = pyqtSignal(float)
    color_changed = pyqtSignal(object)
    opacity_changed = pyqtSignal(float)
    ao_edits_changed = pyqtSignal(object)
    ao_strength_changed = pyqtSignal(float)
    status_changed = pyqtSignal(object)
    camera_read_changed = pyqtSignal(object)
    modified = pyqtSignal(str)
    edited = pyqtSignal(str, bool)

    light_map: Property[lm.LightMap] = Property(lm.preset(lm.DEFAULT_PRESET))
    use_horizon: Property[bool] = Property(False)  # the image's own horizon is given (else the engine reads one)
    horizon: Property[float] = Property(0.0)  # the horizon's canvas row (may lie outside the canvas)
    fov: Property[float] = Property(camera_rules.DEFAULT_FOV)  # the image's vertical field of view, degrees
    color: Property[tuple[float, float, float]] = Property((0.0, 0.0, 0.0))  # the shadow's colour, linear 0..1
    opacity: Property[float] = Property(defaults.OPACITY)
    ao_edits: Property[AoEdits] = Property(AoEdits())  # brush strokes and grow/shrink steps
    ao_strength: Property[float] = Property(1.0)  # scales the contact shadow (AO), 0..MAX_AO_STRENGTH
    status: Property[tuple[str, str]] = Property(("info", READY), readonly=True)  # (level, text for people)
    camera_read: Property[dict | None] = Property(None, readonly=True)  # {"horizon", "fov"} the engine read

    def __init__(self, parent: QObject | None = None) -> None:
        super().__init__(parent)
        self.light_dragging = False  # the last light map edit was a move of a drag (a preview, not the layer)
        self._stroke = 0  # 0: no stroke, each edit a new undo step; 1: a stroke begins; 2: a stroke continues
        self._quiet = False
        self._light_edit = False
        self._camera = self.camera
        self.shadows: dict[str, Settings] = {}  # a shadow layer's id: the settings it was rendered from

    # -- derived -----------------------------------------------------------------------------
    @property
    def camera(self) -> dict | None:
        """The camera the engine uses: ``{"horizon": row, "fov": degrees}``, or None (it reads one itself)."""
        return {"horizon": float(self.horizon), "fov": float(self.fov)} if self.use_horizon else None

    def settings(self) -> Settings:
        """A snapshot of the settings now."""
        return Settings(
            self.light_map.copy(),
            self.use_horizon,
            self.horizon,
            self.fov,
            self.color,
            self.opacity,
            self.ao_edits.copy(),
            self.ao_strength,
        )

    def apply(self, settings: Settings) -> None:
        """Show ``settings`` (loaded, or those of the shadow layer an undo brought back): no edit, nothing
        rendered or saved."""
        with self.quietly():
            self.light_map = settings.light_map.copy()
            self.horizon, self.fov, self.use_horizon = settings.horizon, settings.fov, settings.use_horizon
            self.color, self.opacity = settings.color, settings.opacity
            self.ao_edits, self.ao_strength = settings.ao_edits.copy(), settings.ao_strength

    def ao_edit_list(self) -> list[dict]:
        """The protocol's ``edits`` list (AO edits, then the strength)."""
        return self.ao_edits.to_list(self.ao_strength)

    # -- edits ---------------------------------------------------------------------------------
    def begin_stroke(self) -> None:
        """A continuous edit begins (a slider is pressed): its first change starts an undo step, the rest
        continue it."""
        self._stroke = 1

    def end_stroke(self) -> None:
        self._stroke = 0

    def take_step(self) -> bool:
        """Whether an edit now starts a new undo step (outside a stroke, always; in one, its first edit)."""
        if self._stroke == 1:
            self._stroke = 2
            return True
        return self._stroke == 0

    def edit_light_map(self, light_map: lm.LightMap, new_step: bool, dragging: bool = False) -> None:
        """The editor's map changed (the model keeps a copy). ``dragging``: a move of a light drag (the docker
        previews it; the layer follows at the release, which comes as an edit with ``dragging`` False)."""
        self.light_dragging = dragging
        self._light_edit = True
        try:
            self.light_map = light_map.copy()
        finally:
            self._light_edit = False
        self.edited.emit("light_map", new_step)

    def brush_ao(self, x: float, y: float, radius: float, strength: float, new_stroke: bool) -> None:
        """One dab of the AO brush at frame position (x, y) (0..1); ``strength`` < 0 darkens."""
        edits = self.ao_edits.copy()
        edits.brush(x, y, radius, strength, new_stroke)
        self._set_ao_edits(edits, new_stroke)

    def grow_ao(self, pixels: int) -> None:
        """Grow (> 0) or shrink the contact shadow by ``pixels`` frame pixels."""
        edits = self.ao_edits.copy()
        edits.grow(pixels)
        self._set_ao_edits(edits, True)

    def undo_ao(self) -> None:
        """Remove the last AO stroke or grow step."""
        edits = self.ao_edits.copy()
        if edits.undo():
            self._set_ao_edits(edits, True)

    def reset_ao(self) -> None:
        """No AO edits, full strength."""
        with self.quietly():
            self.ao_strength = 1.0
        self._set_ao_edits(AoEdits(), True)

    def horizon_from_guides(self, guides: list[float]) -> bool:
        """Give the horizon on the guide :func:`camera_rules.horizon_from_guides` takes (canvas rows); False when
        there is no guide."""
        row = camera_rules.horizon_from_guides(guides)
        if row is None:
            return False
        self.horizon = row
        self.use_horizon = True
        return True

    def _set_ao_edits(self, edits: AoEdits, new_step: bool) -> None:
        with self.quietly():
            self.ao_edits = edits
        self.modified.emit("ao_edits")
        self.edited.emit("ao_edits", new_step)

    # -- the controller's reports (derived state) ---------------------------------------------
    def report_status(self, level: str, text: str) -> None:
        """A message for people: level "info", "warning" or "error"."""
        type(self).status.set(self, (level, text))

    def report_camera_read(self, read: dict | None) -> None:
        """The camera the engine read from the cutout's outline (None: it used the given one). Without a given
        horizon, the fields show it (so giving the horizon starts from it); that is no edit."""
        type(self).camera_read.set(self, dict(read) if read is not None else None)
        if read is not None and not self.use_horizon:
            with self.quietly():
                self.horizon = float(round(read["horizon"]))
                self.fov = float(round(read["fov"]))

    def record_shadow(self, layer_id: str, settings: Settings) -> None:
        """The shadow layer ``layer_id`` now shows a shadow rendered from ``settings`` (saved with the document,
        the newest :data:`MAX_SHADOW_RECORDS` layers)."""
        if self.shadows.get(layer_id) == settings:
            return
        self.shadows.pop(layer_id, None)
        self.shadows[layer_id] = settings
        while len(self.shadows) > MAX_SHADOW_RECORDS:
            del self.shadows[next(iter(self.shadows))]
        self.modified.emit("shadows")

    def shadow_shown(self, layer_id: str | None) -> Settings | None:
        """The canvas shows the shadow layer ``layer_id`` (after an undo or redo): show the settings it was
        rendered from, where they are known and differ, and return them (else None). No render: the canvas
        already shows that shadow; the settings are saved as the image's current ones."""
        settings = self.shadows.get(layer_id) if layer_id is not None else None
        if settings is None or settings == self.settings():
            return None
        self.apply(settings)
        self.modified.emit("shadows")
        return settings

    def clear_ao_edits(self) -> None:
        """The cutout is another layer: its AO is new, so the edits of the old one go (saved, no render)."""
        if self.ao_edits.steps or self.ao_strength != 1.0:
            with self.quietly():
                self.ao_edits, self.ao_strength = AoEdits(), 1.0
            self.modified.emit("ao_edits")

    @contextmanager
    def quietly(self) -> Iterator[None]:
        """Changes that the widgets show but that are no user edit (nothing saved, nothing rendered)."""
        quiet, self._quiet = self._quiet, True
        try:
            yield
        finally:
            self._quiet = quiet

    def _property_set(self, name: str) -> None:
        if name in _CAMERA and self._quiet:  # shown or loaded: the camera to compare the next edit with
            self._camera = self.camera
        if name in ("status", "camera_read") or self._quiet:
            return
        self.modified.emit(name)
        if name in _CAMERA:
            camera = self.camera
            if camera != self._camera:
                self._camera = camera
                self.edited.emit("camera", True)
        elif name == "light_map":
            if not self._light_edit:
                self.light_dragging = False
                self.edited.emit("light_map", True)
        elif name in ("ao_edits", "ao_strength"):
            self.edited.emit("ao_edits", self.take_step())
        else:
            self.edited.emit(name, self.take_step())
