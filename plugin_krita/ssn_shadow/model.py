"""The docker's state for one document: its shadow settings, and what the docker shows about it.

One :class:`ShadowModel` per open document (:class:`persistence.DocumentModels`
keeps them). The panel binds its widgets to the model's properties; the
controller renders what the model says and reports back into it (status,
the camera the engine read, the thickness it read, the cutout's ground). The
settings (light map, horizon, colour, opacity, AO edits, lift and thickness)
are saved in the document (:mod:`persistence`).

Signals besides each property's ``<name>_changed``:

- ``modified(name)``: a setting saved with the document changed (by a user edit), or ``"shadows"``: the
  record of which settings made which shadow layer changed;
- ``edited(what, new_step)``: a user edit the shadow depends on, ``what`` one of :data:`EDITS`;
  ``new_step``: the shadow layer's write starts a new undo step (the first change of a slider drag, a
  click) or continues the current one (the rest of the drag).

The artist's geometry (conventions, "Lift and thickness"): ``lift``, canvas rows from the cutout's lowest point
down to the ground beneath it, and ``thickness``, its depth over its width (None: the engine reads it from the
outline, ``thickness_read``). Their edits (:meth:`ShadowModel.edit_lift`, :meth:`ShadowModel.edit_thickness`) are
clamped to what the engine takes (the host kit's :mod:`geometry_clamp`), with the reason in the status.
"""

from __future__ import annotations

from collections.abc import Iterator
from contextlib import contextmanager
from dataclasses import dataclass

from PyQt5.QtCore import QObject, pyqtSignal

from .properties import Property
from .shared import ao_edits, camera_rules, defaults, geometry_clamp
from .shared import light_map as lm

AoEdits = ao_edits.AoEdits  # the kit's AO edit list (a model property shares the module's name)

__all__ = ["EDITS", "MAX_SHADOW_RECORDS", "READY", "Settings", "ShadowModel"]

MAX_SHADOW_RECORDS = 32  # shadow layers whose settings are kept (the newest; older undo steps forget theirs)
READY = "Select the cutout's layer (or a selection) and press Generate."
EDITS = ("light_map", "camera", "color", "opacity", "ao_edits", "geometry")
_GEOMETRY = ("lift", "thickness")
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
    lift: float = 0.0
    thickness: float | None = None


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
    lift_changed = pyqtSignal(float)
    thickness_changed = pyqtSignal(object)
    status_changed = pyqtSignal(object)
    camera_read_changed = pyqtSignal(object)
    thickness_read_changed = pyqtSignal(object)
    ground_changed = pyqtSignal(object)
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
    lift: Property[float] = Property(0.0)  # canvas rows from the cutout's lowest point down to its ground
    thickness: Property[float | None] = Property(None)  # depth over width (None: read from the outline)
    status: Property[tuple[str, str]] = Property(("info", READY), readonly=True)  # (level, text for people)
    camera_read: Property[dict | None] = Property(None, readonly=True)  # {"horizon", "fov"} the engine read
    thickness_read: Property[float | None] = Property(None, readonly=True)  # what the outline reads as
    # the analysed cutout's bbox [x0, y0, x1, y1], its canvas's (width, height) and the row its lift counts from
    # (its lowest pixel's, above a soft edge's last rows): where its ground point is
    ground: Property[tuple[tuple[int, int, int, int], tuple[int, int], int] | None] = Property(None, readonly=True)

    def __init__(self, parent: QObject | None = None) -> None:
        super().__init__(parent)
        self.light_dragging = False  # the last light map edit was a move of a drag (a preview, not the layer)
        self.geometry_dragging = False  # the last lift or thickness edit was a move of a drag (the same)
        self.clamped = ""  # why the last lift or thickness was clamped, for the status after its render
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
            self.lift,
            self.thickness,
        )

    def apply(self, settings: Settings) -> None:
        """Show ``settings`` (loaded, or those of the shadow layer an undo brought back): no edit, nothing
        rendered or saved."""
        with self.quietly():
            self.light_map = settings.light_map.copy()
            self.horizon, self.fov, self.use_horizon = settings.horizon, settings.fov, settings.use_horizon
            self.color, self.opacity = settings.color, settings.opacity
            self.ao_edits, self.ao_strength = settings.ao_edits.copy(), settings.ao_strength
            self.lift, self.thickness = settings.lift, settings.thickness

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

    def dragging(self, what: str) -> bool:
        """Whether the last edit of ``what`` ("light_map" or "geometry") was a move of a drag."""
        return self.light_dragging if what == "light_map" else what == "geometry" and self.geometry_dragging

    def edit_lift(self, lift: float, new_step: bool = True, dragging: bool = False) -> None:
        """The lift box, slider or the preview's handle set ``lift`` canvas rows: clamped to what the engine takes
        (0 to 20 canvas heights, and a ground below the horizon of the camera in use), the reason in the status.
        ``dragging``: a move of a drag (previewed; the layer follows at the release, an edit with it False)."""
        lift, why = geometry_clamp.clamp_lift(lift, *self._lift_bounds())
        self._say_clamped(why)
        self._edit_geometry(lift, self.thickness, new_step, dragging)

    def edit_thickness(self, thickness: float | None, new_step: bool = True, dragging: bool = False) -> None:
        """The thickness slider set ``thickness`` (None: read from the outline), clamped as :meth:`edit_lift`."""
        if thickness is not None:
            thickness, why = geometry_clamp.clamp_thickness(thickness)
            self._say_clamped(why)
        self._edit_geometry(self.lift, thickness, new_step, dragging)

    def reset_geometry(self) -> None:
        """Rest on the ground, the thickness read from the outline: one edit."""
        self._edit_geometry(0.0, None, True, False)

    def clamp_geometry(self) -> bool:
        """Clamp the lift to the cutout's ground and the camera now known (a camera changed, a cutout analysed),
        saying why; True if it changed (saved, no render: the render that asked is under way)."""
        lift, why = geometry_clamp.clamp_lift(self.lift, *self._lift_bounds())
        if lift == self.lift:
            return False
        self._say_clamped(why)
        with self.quietly():
            self.lift = lift
        self.modified.emit("geometry")
        return True

    def _say_clamped(self, why: str) -> None:
        """A value clamped: why, in the status now and (:attr:`clamped`) after the render it asks for."""
        if why:
            self.clamped = why
            self.report_status("warning", why)

    def _lift_bounds(self) -> tuple[int, float | None, float | None]:
        """The canvas height, the cutout's lowest row and the horizon of the camera in use, where known."""
        ground = self.ground
        if ground is None:
            return 1 << 30, None, None  # no cutout yet: only the sign is known
        camera = self.camera or self.camera_read
        return ground[1][1], ground[2], None if camera is None else float(camera["horizon"])

    def _edit_geometry(self, lift: float, thickness: float | None, new_step: bool, dragging: bool) -> None:
        ending = self.geometry_dragging and not dragging
        self.geometry_dragging = dragging
        changed = (lift, thickness) != (self.lift, self.thickness)
        if changed:
            with self.quietly():
                self.lift, self.thickness = lift, thickness
            self.modified.emit("geometry")
        if changed or ending:  # a drag's release is an edit where it rests (it writes the layer)
            self.edited.emit("geometry", new_step)

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

    def report_geometry(self, reply: dict) -> None:
        """The worker's ``set_geometry`` reply: the thickness the outline reads as (for the slider's label)."""
        read = reply.get("thickness_read")
        type(self).thickness_read.set(self, float(read) if isinstance(read, (int, float)) else None)

    def report_ground(self, bbox: list | tuple, canvas: tuple[int, int], lift_row: object = None) -> None:
        """The analysed cutout's bbox on its canvas of ``canvas`` (width, height) and the canvas row its lift counts
        from (the worker's ``lift_row``; its bbox's lowest row where the reply has none): the lift handle's place."""
        x0, y0, x1, y1 = (int(v) for v in bbox)
        row = int(lift_row) if isinstance(lift_row, (int, float)) and not isinstance(lift_row, bool) else y1 - 1
        type(self).ground.set(self, ((x0, y0, x1, y1), (int(canvas[0]), int(canvas[1])), row))

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
        if name in ("status", "camera_read", "thickness_read", "ground") or self._quiet:
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
        elif name in _GEOMETRY:
            self.geometry_dragging = False
            self.edited.emit("geometry", self.take_step())
        else:
            self.edited.emit(name, self.take_step())
