"""The docker's content: light map editor, AO preview and tools, shadow options, Generate/Live."""

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

from ..shared import ao_edits, camera_rules, defaults
from ..shared import light_map as lm

from .ao_preview import AOPreview
from .drag_preview import DragPreview
from .light_map_widget import LightMapWidget, slider_to_softness, softness_to_slider

LEVEL_COLOURS = {"info": "", "warning": "color: #d08000;", "error": "color: #d03030;"}
NO_GUIDE = "Add a horizontal guide on the horizon first (drag one down from the top ruler), then press From guide."


def _slider(lo: int, hi: int, value: int) -> QSlider:
    s = QSlider(Qt.Orientation.Horizontal)
    s.setRange(lo, hi)
    s.setValue(value)
    return s


class ShadowPanel(QWidget):
    """All controls; talks only to a ShadowController."""

    def __init__(self, controller, parent: QWidget | None = None) -> None:
        super().__init__(parent)
        self.controller = controller
        self.ao_edits = ao_edits.AoEdits()
        self._syncing = False
        self._build()
        self._wire()
        self._sync_light_controls()

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
        self.map_widget = LightMapWidget(self.controller.light_map.copy())
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
        self._show_camera(None)

        shadow_box = QGroupBox("Shadow")
        sf = QFormLayout(shadow_box)
        self.color_button = QPushButton()
        self.color_button.setToolTip("Shadow colour")
        self._show_colour()
        self.opacity = _slider(0, 100, round(100 * self.controller.opacity))
        sf.addRow("Colour", self.color_button)
        sf.addRow("Opacity", self.opacity)
        root.addWidget(shadow_box)

        row = QHBoxLayout()
        self.live = QCheckBox("Live")
        self.live.setToolTip("Follow the lights as they change: a preview above the map while a light is dragged")
        self.live.setChecked(self.controller.live)
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
        self.message = QLabel("Select the cutout's layer (or a selection) and press Generate.")
        self.message.setWordWrap(True)
        self.message.setTextInteractionFlags(Qt.TextInteractionFlag.TextSelectableByMouse)
        root.addWidget(self.message)
        root.addStretch(1)

    def _wire(self) -> None:
        c = self.controller
        self.generate.clicked.connect(self._guard(lambda *_: c.generate()))
        self.live.toggled.connect(self._guard(self._set_live))
        self.presets.activated.connect(self._guard(self._choose_preset))
        self.map_widget.lightsChanged.connect(self._guard(self._lights_changed))
        self.map_widget.selectionChanged.connect(self._guard(lambda _: self._sync_light_controls()))
        self.softness.valueChanged.connect(self._guard(self._softness_moved))
        self.intensity.valueChanged.connect(self._guard(self._intensity_moved))
        self.softness.sliderPressed.connect(self._guard(self._slider_pressed))
        self.intensity.sliderPressed.connect(self._guard(self._slider_pressed))
        self.ao_preview.brushed.connect(self._guard(self._brush))
        self.brush_size.valueChanged.connect(self._guard(self._brush_size))
        self.grow.clicked.connect(self._guard(lambda *_: self._grow(2)))
        self.shrink.clicked.connect(self._guard(lambda *_: self._grow(-2)))
        self.ao_strength.valueChanged.connect(self._guard(self._ao_strength))
        self.ao_strength.sliderPressed.connect(self._guard(self._slider_pressed))
        self.ao_undo.clicked.connect(self._guard(lambda *_: self._undo_ao()))
        self.ao_reset.clicked.connect(self._guard(lambda *_: self._reset_ao()))
        self.color_button.clicked.connect(self._guard(lambda *_: self._pick_colour()))
        self.opacity.valueChanged.connect(self._guard(self._opacity))
        self.opacity.sliderPressed.connect(self._guard(self._slider_pressed))
        self.use_horizon.toggled.connect(self._guard(lambda *_: self._camera_edited()))
        self.horizon.editingFinished.connect(self._guard(self._camera_edited))
        self.fov.editingFinished.connect(self._guard(self._camera_edited))
        self.from_guide.clicked.connect(self._guard(lambda *_: self._horizon_from_guide()))
        self.cancel.clicked.connect(self._guard(lambda *_: c.cancel()))
        c.busyChanged.connect(self._guard(self._show_busy))
        c.status.connect(self._guard(self.show_message))
        c.aoChanged.connect(self._guard(self.ao_preview.set_images))
        c.previewed.connect(self._guard(self.drag_preview.set_image))
        c.engineReady.connect(self._guard(self._engine_ready))
        c.cameraRead.connect(self._guard(self._show_camera_read))
        self._stroke = False

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
        self.map_widget.setToolTip(self.map_widget.toolTip())
        self.setToolTip(f"Shadow engine {info.get('version', '?')}: {note}")

    # -- lights --------------------------------------------------------------------------
    def _set_live(self, on: bool) -> None:
        self.controller.live = on

    def _choose_preset(self, index: int) -> None:
        if index <= 0:
            return
        name = self.presets.itemText(index)
        self.presets.setCurrentIndex(0)
        self.map_widget.editor.load(lm.preset(name))
        self._sync_light_controls()

    def _lights_changed(self, live: bool, new_stroke: bool) -> None:
        self._sync_light_controls()
        if live and self.map_widget.editor.dragging:  # a preview in the docker; the layer on release
            self.controller.drag_light_map(self.map_widget.light_map)  # it keeps a copy
        else:
            self.controller.set_light_map(self.map_widget.light_map, new_stroke)

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

    def _slider_pressed(self) -> None:
        self._stroke = True

    def _take_stroke(self) -> bool:
        started, self._stroke = self._stroke, False
        return started

    def _softness_moved(self, value: int) -> None:
        if not self._syncing:  # the widget's lightsChanged re-renders
            started = self._take_stroke() or not self.softness.isSliderDown()
            self.map_widget.editor.set_softness(slider_to_softness(value), started)

    def _intensity_moved(self, value: int) -> None:
        if not self._syncing:
            started = self._take_stroke() or not self.intensity.isSliderDown()
            self.map_widget.editor.set_intensity(value / 100.0, started)

    # -- AO ----------------------------------------------------------------------------------
    def _brush_size(self, value: int) -> None:
        self.ao_preview.brush_radius = value / 100.0

    def _brush(self, x: float, y: float, started: bool) -> None:
        sign = -1.0 if self.darken.isChecked() else 1.0
        self.ao_edits.brush(x, y, self.brush_size.value() / 100.0, sign * self.brush_strength.value() / 100.0, started)
        self.controller.set_ao_edits(self.ao_edits.to_list(), started)

    def _grow(self, pixels: int) -> None:
        self.ao_edits.grow(pixels)
        self.controller.set_ao_edits(self.ao_edits.to_list(), True)

    def _ao_strength(self, value: int) -> None:
        if self._syncing:
            return
        self.ao_edits.strength = value / 100.0
        started = self._take_stroke() or not self.ao_strength.isSliderDown()
        self.controller.set_ao_edits(self.ao_edits.to_list(), started)

    def _undo_ao(self) -> None:
        if self.ao_edits.undo():
            self.controller.set_ao_edits(self.ao_edits.to_list(), True)

    def _reset_ao(self) -> None:
        self.ao_edits.reset()
        self._syncing = True
        self.ao_strength.setValue(100)
        self._syncing = False
        self.controller.set_ao_edits([], True)

    # -- camera ----------------------------------------------------------------------------
    def _show_camera(self, camera: dict | None) -> None:
        """Show a camera (None: the default) without sending it."""
        self._syncing = True
        self.use_horizon.setChecked(camera is not None)
        if camera is not None:
            self.horizon.setValue(round(camera["horizon"]))
            self.fov.setValue(camera.get("fov", camera_rules.DEFAULT_FOV))
        for w in (self.horizon, self.fov):
            w.setEnabled(camera is not None)
        self._syncing = False
        self._show_camera_read(None)

    def _show_camera_read(self, read: dict | None) -> None:
        """Without a camera of the image's own, show the one the model read from the outline in the (disabled)
        fields, so that ticking the box starts from it."""
        if read is None or self.use_horizon.isChecked():
            self.camera_read.setText("")
            self.camera_read.setVisible(False)
            return
        shown = camera_rules.camera_read_settings(read)
        self._syncing = True
        self.horizon.setValue(round(shown["horizon"]))
        self.fov.setValue(shown["fov"])
        self._syncing = False
        source = self.controller.source  # the cutout's image, whose camera the model read
        self.camera_read.setText(camera_rules.camera_read_note(read, source.height if source is not None else 0))
        self.camera_read.setVisible(True)

    def _camera_edited(self) -> None:
        if self._syncing:
            return
        on = self.use_horizon.isChecked()
        for w in (self.horizon, self.fov):
            w.setEnabled(on)
        camera = {"horizon": float(self.horizon.value()), "fov": float(self.fov.value())} if on else None
        if on:
            self._show_camera_read(None)
        if camera != self.controller.camera:
            self.controller.set_camera(camera)

    def _horizon_from_guide(self) -> None:
        document = self.controller.host.active_document()
        guides = list(document.horizontalGuides()) if document is not None else []
        if not guides:
            self.show_message("warning", NO_GUIDE)
            return
        self._syncing = True
        self.horizon.setValue(round(guides[0]))
        self.use_horizon.setChecked(True)
        self._syncing = False
        self._camera_edited()

    def document_changed(self, document) -> None:
        """Another document is active: show (and use) the camera remembered for it."""
        camera = self.controller.camera_for(document)
        self.controller.camera = camera
        self._show_camera(camera)

    # -- shadow ----------------------------------------------------------------------------
    def _show_colour(self) -> None:
        r, g, b = (round(255 * c) for c in self.controller.color)
        self.color_button.setStyleSheet(f"background-color: rgb({r}, {g}, {b}); min-height: 18px;")

    def _pick_colour(self) -> None:
        r, g, b = (round(255 * c) for c in self.controller.color)
        colour = QColorDialog.getColor(QColor(r, g, b), self, "Shadow colour")
        if colour.isValid():
            self.set_colour((colour.redF(), colour.greenF(), colour.blueF()))

    def set_colour(self, rgb: tuple[float, float, float]) -> None:
        self.controller.color = tuple(float(c) for c in rgb)
        self._show_colour()
        self.controller.lights_edited(True)

    def _opacity(self, value: int) -> None:
        self.controller.opacity = value / 100.0
        self.controller.lights_edited(self._take_stroke() or not self.opacity.isSliderDown())
