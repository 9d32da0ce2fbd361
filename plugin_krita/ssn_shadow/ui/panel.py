"""The docker's content: light map editor, AO preview and tools, camera, shadow options, Generate/Live.

The panel shows one document's :class:`model.ShadowModel` (the controller's
current one) through bindings: each widget shows a property and its edits set
that property. It reaches Krita only through the controller's actions
(Generate, From guide, Cancel).
"""

from __future__ import annotations

from PyQt5.QtCore import Qt
from PyQt5.QtGui import QColor
from PyQt5.QtWidgets import (
    QCheckBox,
    QColorDialog,
    QComboBox,
    QDoubleSpinBox,
    QFormLayout,
    QGroupBox,
    QHBoxLayout,
    QLabel,
    QProgressBar,
    QPushButton,
    QRadioButton,
    QSlider,
    QSpinBox,
    QVBoxLayout,
    QWidget,
)

from ..model import ShadowModel
from ..properties import Binding, bind
from ..shared import camera_rules, defaults
from ..shared import light_map as lm

from .ao_preview import AOPreview
from .drag_preview import DragPreview
from .light_map_widget import LightMapWidget, slider_to_softness, softness_to_slider

LEVEL_COLOURS = {"info": "", "warning": "color: #d08000;", "error": "color: #d03030;"}


def _slider(lo: int, hi: int, value: int) -> QSlider:
    s = QSlider(Qt.Orientation.Horizontal)
    s.setRange(lo, hi)
    s.setValue(value)
    return s


class ShadowPanel(QWidget):
    """All controls, bound to the controller's model; the actions go to the controller."""

    def __init__(self, controller, parent: QWidget | None = None) -> None:
        super().__init__(parent)
        self.controller = controller
        self.model: ShadowModel = controller.model
        self._bindings: list[Binding] = []
        self._syncing = False  # the light sliders show the selected light (no edit)
        self._showing_map = False  # the map widget shows the model's map (no edit)
        self._build()
        self._wire()
        self.show_model(controller.model)

    # -- layout ----------------------------------------------------------------------
    def _build(self) -> None:
        root = QVBoxLayout(self)
        root.setContentsMargins(4, 4, 4, 4)

        light_box = QGroupBox("Light")
        lv = QVBoxLayout(light_box)
        self.presets = QComboBox()
        self.presets.addItem("Preset…")
        self.presets.addItems(list(lm.PRESETS))
        lv.addWidget(self.presets)
        self.drag_preview = DragPreview()
        lv.addWidget(self.drag_preview)
        self.map_widget = LightMapWidget(lm.LightMap())
        lv.addWidget(self.map_widget)
        form = QFormLayout()
        self.softness = _slider(0, 100, 50)
        self.intensity = _slider(0, 300, 100)
        form.addRow("Softness", self.softness)
        form.addRow("Intensity", self.intensity)
        lv.addLayout(form)
        hint = QLabel(
            "A light casts its shadow the opposite way: right of centre, to the left; low, long. "
            "Click: add · drag: move · wheel: softness · Shift+wheel: intensity · right-click / Del: remove"
        )
        hint.setWordWrap(True)
        hint.setStyleSheet("color: gray; font-size: 8pt;")
        lv.addWidget(hint)
        root.addWidget(light_box)

        ao_box = QGroupBox("Ambient occlusion")
        av = QVBoxLayout(ao_box)
        self.ao_preview = AOPreview()
        av.addWidget(self.ao_preview)
        tools = QHBoxLayout()
        self.darken = QRadioButton("Darken")
        self.lighten = QRadioButton("Lighten")
        self.darken.setChecked(True)
        tools.addWidget(self.darken)
        tools.addWidget(self.lighten)
        self.grow = QPushButton("Grow")
        self.shrink = QPushButton("Shrink")
        tools.addWidget(self.grow)
        tools.addWidget(self.shrink)
        av.addLayout(tools)
        aform = QFormLayout()
        self.brush_size = _slider(1, 25, 5)  # radius in % of the frame
        self.brush_strength = _slider(5, 100, 50)
        self.ao_strength = _slider(0, round(100 * defaults.MAX_AO_STRENGTH), 100)
        aform.addRow("Brush size", self.brush_size)
        aform.addRow("Brush strength", self.brush_strength)
        aform.addRow("AO strength", self.ao_strength)
        av.addLayout(aform)
        arow = QHBoxLayout()
        self.ao_undo = QPushButton("Undo AO edit")
        self.ao_reset = QPushButton("Reset AO")
        arow.addWidget(self.ao_undo)
        arow.addWidget(self.ao_reset)
        av.addLayout(arow)
        root.addWidget(ao_box)

        camera_box = QGroupBox("Camera")
        cv = QVBoxLayout(camera_box)
        self.use_horizon = QCheckBox("The image's horizon is at")
        self.use_horizon.setToolTip("Without it the engine reads the camera from the cutout's outline")
        hrow = QHBoxLayout()
        self.horizon = QSpinBox()
        self.horizon.setRange(*(round(b) for b in camera_rules.EDITOR_HORIZON_RANGE))
        self.horizon.setSuffix(" px")
        self.horizon.setToolTip("The canvas row where the ground meets the sky (it may lie above or below the image)")
        self.from_guide = QPushButton("From guide")
        self.from_guide.setToolTip("Use the first horizontal guide as the horizon")
        hrow.addWidget(self.horizon, 1)
        hrow.addWidget(self.from_guide)
        cform = QFormLayout()
        self.fov = QDoubleSpinBox()
        self.fov.setRange(*camera_rules.EDITOR_FOV_RANGE)
        self.fov.setDecimals(0)
        self.fov.setSuffix("°")
        self.fov.setValue(camera_rules.DEFAULT_FOV)
        self.fov.setToolTip("The image's vertical field of view (a phone camera: about 50 degrees)")
        cform.addRow("Field of view", self.fov)
        self.camera_read = QLabel()
        self.camera_read.setWordWrap(True)
        cv.addWidget(self.use_horizon)
        cv.addLayout(hrow)
        cv.addLayout(cform)
        cv.addWidget(self.camera_read)
        root.addWidget(camera_box)

        shadow_box = QGroupBox("Shadow")
        sf = QFormLayout(shadow_box)
        self.color_button = QPushButton()
        self.color_button.setToolTip("Shadow colour")
        self.opacity = _slider(0, 100, round(100 * defaults.OPACITY))
        sf.addRow("Colour", self.color_button)
        sf.addRow("Opacity", self.opacity)
        root.addWidget(shadow_box)

        row = QHBoxLayout()
        self.live = QCheckBox("Live")
        self.live.setToolTip("Follow the lights as they change: a preview above the map while a light is dragged")
        self.generate = QPushButton("Generate shadow")
        self.generate.setDefault(True)
        row.addWidget(self.live)
        row.addWidget(self.generate, 1)
        root.addLayout(row)
        self.busy = QProgressBar()
        self.busy.setRange(0, 0)  # an indeterminate busy indicator
        self.busy.setMaximumHeight(8)
        self.busy.setTextVisible(False)
        self.busy.setVisible(False)
        self.cancel = QPushButton("Cancel")
        self.cancel.setToolTip("Stop waiting for the shadow engine (it restarts with the next Generate)")
        self.cancel.setVisible(False)
        busy_row = QHBoxLayout()
        busy_row.addWidget(self.busy, 1)
        busy_row.addWidget(self.cancel)
        root.addLayout(busy_row)
        self.message = QLabel()
        self.message.setWordWrap(True)
        self.message.setTextInteractionFlags(Qt.TextInteractionFlag.TextSelectableByMouse)
        root.addWidget(self.message)
        root.addStretch(1)

    def _wire(self) -> None:
        """The connections that do not depend on the document: actions, tools, the controller's state."""
        c, guard = self.controller, self._guard
        self.generate.clicked.connect(guard(lambda *_: c.generate()))
        self.cancel.clicked.connect(guard(lambda *_: c.cancel()))
        self.from_guide.clicked.connect(guard(lambda *_: c.horizon_from_guide()))
        self.presets.activated.connect(guard(self._choose_preset))
        self.map_widget.lightsChanged.connect(guard(self._lights_changed))
        self.map_widget.selectionChanged.connect(guard(lambda _: self._sync_light_controls()))
        self.softness.valueChanged.connect(guard(self._softness_moved))
        self.intensity.valueChanged.connect(guard(self._intensity_moved))
        self.ao_preview.brushed.connect(guard(self._brush))
        self.brush_size.valueChanged.connect(guard(self._brush_size))
        self.grow.clicked.connect(guard(lambda *_: self.model.grow_ao(2)))
        self.shrink.clicked.connect(guard(lambda *_: self.model.grow_ao(-2)))
        self.ao_undo.clicked.connect(guard(lambda *_: self.model.undo_ao()))
        self.ao_reset.clicked.connect(guard(lambda *_: self.model.reset_ao()))
        self.color_button.clicked.connect(guard(lambda *_: self._pick_colour()))
        for slider in (self.softness, self.intensity, self.ao_strength, self.opacity):  # a drag: one undo step
            slider.sliderPressed.connect(guard(lambda: self.model.begin_stroke()))
            slider.sliderReleased.connect(guard(lambda: self.model.end_stroke()))
        bind(c, "live", self.live.setChecked, self.live.toggled, guard(lambda on: setattr(c, "live", on)))
        bind(c, "busy", guard(self._show_busy))
        c.aoChanged.connect(guard(self.ao_preview.set_images))
        c.previewed.connect(guard(self.drag_preview.set_image))
        c.engineReady.connect(guard(self._engine_ready))

    def show_model(self, model: ShadowModel) -> None:
        """Show (and edit) ``model``: the controller's, after it changed to another document's."""
        for binding in self._bindings:
            binding.disconnect()
        self.model, guard = model, self._guard
        self._bindings = [
            bind(model, "light_map", guard(self._show_light_map)),
            bind(
                model,
                "ao_strength",
                lambda v: self.ao_strength.setValue(round(100 * v)),
                self.ao_strength.valueChanged,
                guard(lambda v: setattr(model, "ao_strength", v / 100.0)),
            ),
            bind(
                model,
                "use_horizon",
                guard(self._show_use_horizon),
                self.use_horizon.toggled,
                guard(lambda on: setattr(model, "use_horizon", on)),
            ),
            bind(
                model,
                "horizon",
                lambda v: self.horizon.setValue(round(v)),
                self.horizon.editingFinished,
                guard(lambda: setattr(model, "horizon", float(self.horizon.value()))),
            ),
            bind(
                model,
                "fov",
                self.fov.setValue,
                self.fov.editingFinished,
                guard(lambda: setattr(model, "fov", float(self.fov.value()))),
            ),
            bind(model, "camera_read", guard(lambda _: self._show_camera_read())),
            bind(model, "color", guard(self._show_colour)),
            bind(
                model,
                "opacity",
                lambda v: self.opacity.setValue(round(100 * v)),
                self.opacity.valueChanged,
                guard(lambda v: setattr(model, "opacity", v / 100.0)),
            ),
            bind(model, "status", guard(lambda status: self.show_message(*status))),
        ]

    def _guard(self, fn):
        """Catch everything at the UI boundary and show it in the docker instead."""

        def wrapped(*args):
            try:
                return fn(*args)
            except Exception as exc:  # never crash the host
                self.show_message("error", f"Soft Shadow: {type(exc).__name__}: {exc}")
                return None

        return wrapped

    # -- messages ----------------------------------------------------------------------
    def show_message(self, level: str, text: str) -> None:
        self.message.setStyleSheet(LEVEL_COLOURS.get(level, ""))
        self.message.setText(text)

    def _show_busy(self, busy: bool) -> None:
        self.busy.setVisible(busy)
        self.cancel.setVisible(busy)

    def _engine_ready(self, info: dict) -> None:
        note = info.get("method_note") or info.get("method", "")
        self.setToolTip(f"Shadow engine {info.get('version', '?')}: {note}")

    # -- lights --------------------------------------------------------------------------
    def _show_light_map(self, light_map: lm.LightMap) -> None:
        if self.map_widget.light_map != light_map:  # else the widget's own edit: it shows it already
            self._showing_map = True
            try:
                self.map_widget.editor.load(light_map.copy())
            finally:
                self._showing_map = False
        self._sync_light_controls()

    def _choose_preset(self, index: int) -> None:
        if index <= 0:
            return
        name = self.presets.itemText(index)
        self.presets.setCurrentIndex(0)
        self.model.light_map = lm.preset(name)

    def _lights_changed(self, live: bool, new_stroke: bool) -> None:
        if self._showing_map:
            return
        self._sync_light_controls()
        dragging = live and self.map_widget.editor.dragging  # a preview in the docker; the layer on release
        self.model.edit_light_map(self.map_widget.light_map, new_stroke, dragging)

    def _sync_light_controls(self) -> None:
        i = self.map_widget.selected
        light = self.map_widget.light_map.lights[i] if i is not None and i < len(self.map_widget.light_map) else None
        self.softness.setEnabled(light is not None)
        self.intensity.setEnabled(light is not None)
        if light is not None:
            self._syncing = True
            self.softness.setValue(softness_to_slider(light.softness))
            self.intensity.setValue(round(100 * light.intensity))
            self._syncing = False

    def _softness_moved(self, value: int) -> None:
        if not self._syncing:  # the widget's lightsChanged edits the model
            self.map_widget.editor.set_softness(slider_to_softness(value), self.model.take_step())

    def _intensity_moved(self, value: int) -> None:
        if not self._syncing:
            self.map_widget.editor.set_intensity(value / 100.0, self.model.take_step())

    # -- AO ----------------------------------------------------------------------------------
    def _brush_size(self, value: int) -> None:
        self.ao_preview.brush_radius = value / 100.0

    def _brush(self, x: float, y: float, started: bool) -> None:
        sign = -1.0 if self.darken.isChecked() else 1.0
        self.model.brush_ao(x, y, self.brush_size.value() / 100.0, sign * self.brush_strength.value() / 100.0, started)

    # -- camera ----------------------------------------------------------------------------
    def _show_use_horizon(self, given: bool) -> None:
        self.use_horizon.setChecked(given)
        for w in (self.horizon, self.fov):
            w.setEnabled(given)
        self._show_camera_read()

    def _show_camera_read(self) -> None:
        """Without a horizon of the image's own, say which camera the model read from the outline (the disabled
        fields show it, so that ticking the box starts from it)."""
        read = self.model.camera_read
        if read is None or self.model.use_horizon:
            self.camera_read.setText("")
            self.camera_read.setVisible(False)
            return
        source = self.controller.source  # the cutout's image, whose camera the model read
        self.camera_read.setText(camera_rules.camera_read_note(read, source.height if source is not None else 0))
        self.camera_read.setVisible(True)

    # -- shadow ----------------------------------------------------------------------------
    def _show_colour(self, rgb: tuple[float, float, float]) -> None:
        r, g, b = (round(255 * c) for c in rgb)
        self.color_button.setStyleSheet(f"background-color: rgb({r}, {g}, {b}); min-height: 18px;")

    def _pick_colour(self) -> None:
        r, g, b = (round(255 * c) for c in self.model.color)
        colour = QColorDialog.getColor(QColor(r, g, b), self, "Shadow colour")
        if colour.isValid():
            self.model.color = (colour.redF(), colour.greenF(), colour.blueF())
