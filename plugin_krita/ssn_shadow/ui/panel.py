"""The docker's content: light map editor, AO preview and tools, camera, shadow options, Generate/Live.

The panel shows one document's :class:`model.ShadowModel` (the controller's
current one) through bindings: each widget shows a property and its edits set
that property. It reaches Krita only through the controller's actions
(Generate, From guide, Cancel).

Its layout holds still under the mouse: the controls scroll in a body as
narrow as a default dock (the map and previews scale to the width, labels
wrap), Generate and the status stay in a footer below it, the shadow preview
and the camera note keep their space whatever they show.

The light editor (the sky map, then the preset, Size and Intensity) comes first; the preview, the ambient
occlusion, the camera and the shadow's colour and opacity are sections that fold, folded at first in a short
dock (:mod:`.folding` decides which), and the artist's choice to fold or unfold one is remembered (Qt's
settings). In a short dock the map is no taller than the scroll area shows, so it and Generate are in view.
"""

from __future__ import annotations

from PyQt5.QtCore import QEvent, QObject, QSettings, QSize, Qt, pyqtSignal
from PyQt5.QtGui import QColor
from PyQt5.QtWidgets import (
    QCheckBox,
    QColorDialog,
    QComboBox,
    QDoubleSpinBox,
    QFormLayout,
    QHBoxLayout,
    QLabel,
    QProgressBar,
    QPushButton,
    QRadioButton,
    QScrollArea,
    QSizePolicy,
    QSlider,
    QSpinBox,
    QToolButton,
    QVBoxLayout,
    QWidget,
)

from ..model import ShadowModel
from ..properties import Binding, bind
from ..shared import camera_rules, defaults, geometry_rules
from ..shared import light_editor
from ..shared import light_map as lm
from ..shared import light_size

from . import folding
from .ao_preview import AOPreview
from .light_map_widget import LightMapWidget
from .shadow_preview import ShadowPreview

LEVEL_COLOURS = {"info": "", "warning": "color: #d08000;", "error": "color: #d03030;"}
CUSTOM = "Custom"  # the preset box when the lights are no preset's
PRESET_TITLES = {  # the presets' names for people (files and the CLI use the keys)
    "high-sun": "High sun",
    "low-sun-left": "Low sun, left",
    "low-sun-right": "Low sun, right",
    "overcast": "Overcast",
    "softbox": "Softbox",
    "two-lights": "Two lights",
    "rim-light": "Rim light",
}
PANEL_WIDTH = 300  # pixels: the panel's preferred width (it fits narrower docks: the map and previews scale)
HINT_WIDTH = 240  # pixels: the width a wrapped label's size hint assumes (the layout asks at its real width)
BODY_MARGIN = 4  # pixels around the scrolling controls
SETTINGS = ("ssn-shadow", "krita-docker")  # QSettings' organisation and application: the fold choices
UNKNOWN = "\u2014"  # a camera field's text while no camera is known (an em dash)
CAMERA_NOTES = {
    "unknown": "At Generate the engine reads the horizon and field of view from the cutout's outline; tick "
    "the box to give them yourself.",
    "given": "Given: the shadow's perspective follows this horizon and field of view. Untick the box to let the "
    "engine read them from the cutout's outline.",
}


LIFT_HINT = (
    "How far the object floats: canvas rows from its lowest point down to the ground beneath it (0 rests on the "
    "ground). Drag the bar under the object in the preview, or type it."
)
THICKNESS_HINT = "The object's depth over its width: 0 a flat sign, 1 a ball, about 2 a person from the side, 8 deep."
LIFT_SLIDER_ROWS = 500  # the lift slider's range before a cutout is known (then its canvas height; the box: more)
MAX_BOX = 99999  # the lift box's range before a cutout is known (the model clamps; the box is as wide as its range)


def thickness_text(thickness: float | None, read: float | None) -> str:
    """The thickness slider's label: the value set, or the reading it uses ("Thickness: read 0.29")."""
    if thickness is not None:
        return f"Thickness: {thickness:.2f}"
    return "Thickness: read from the outline" if read is None else f"Thickness: read {read:.2f}"


def preset_title(name: str) -> str:
    """A preset's name for people ("low-sun-left": "Low sun, left")."""
    return PRESET_TITLES.get(name) or name.replace("-", " ").capitalize()


class CameraField:
    """A spin box mixin that shows a dash instead of its value while no camera is known."""

    unit = ""

    def set_unknown(self, unknown: bool) -> None:
        self._unknown = unknown
        self.setSuffix("" if unknown else self.unit)  # type: ignore[attr-defined]  # also redraws the text

    def textFromValue(self, value) -> str:  # noqa: N802 (Qt's API)
        if getattr(self, "_unknown", False):
            return UNKNOWN
        return super().textFromValue(value)  # type: ignore[misc]


class HorizonField(CameraField, QSpinBox):
    unit = " px"


class FovField(CameraField, QDoubleSpinBox):
    unit = "°"


class SteadyLabel(QLabel):
    """A word-wrapped label as tall as the tallest of its possible texts, so that a change of text moves
    nothing below it."""

    def __init__(self, texts: list[str], parent: QWidget | None = None) -> None:
        super().__init__(parent)
        self.texts = texts
        self.setWordWrap(True)
        policy = QSizePolicy(QSizePolicy.Policy.Ignored, QSizePolicy.Policy.Fixed)  # it wraps to any width
        policy.setHeightForWidth(True)
        self.setSizePolicy(policy)

    def heightForWidth(self, width: int) -> int:  # noqa: N802 (Qt's API)
        margins = self.contentsMargins()
        inner = max(1, width - margins.left() - margins.right())
        metrics = self.fontMetrics()
        flags = int(Qt.TextFlag.TextWordWrap)
        tallest = max(metrics.boundingRect(0, 0, inner, 1 << 20, flags, text).height() for text in self.texts)
        return max(super().heightForWidth(width), tallest + margins.top() + margins.bottom())

    def sizeHint(self) -> QSize:
        return QSize(HINT_WIDTH, self.heightForWidth(HINT_WIDTH))

    def minimumSizeHint(self) -> QSize:
        return QSize(0, self.heightForWidth(HINT_WIDTH))


class FoldChoices:
    """The sections the artist folded or unfolded, kept in Qt's settings (``SETTINGS``, key ``folds/<section>``):
    the next Krita shows them so."""

    def __init__(self, settings: QSettings | None = None) -> None:
        self.settings = settings if settings is not None else QSettings(*SETTINGS)

    def chosen(self) -> dict[str, bool]:
        s = self.settings
        return {n: s.value(f"folds/{n}", type=bool) for n in folding.SECTIONS if s.contains(f"folds/{n}")}

    def choose(self, name: str, opened: bool) -> None:
        self.settings.setValue(f"folds/{name}", opened)
        self.settings.sync()


class Section(QWidget):
    """A titled part of the panel that folds: a header button (an arrow and the title) over its content."""

    chosen = pyqtSignal(str, bool)  # the artist folded (False) or unfolded (True) the section

    def __init__(self, name: str, content: QWidget, parent: QWidget | None = None) -> None:
        super().__init__(parent)
        self.name, self.content = name, content
        self.header = QToolButton()
        self.header.setText(folding.TITLES[name])
        self.header.setCheckable(True)
        self.header.setAutoRaise(True)
        self.header.setToolButtonStyle(Qt.ToolButtonStyle.ToolButtonTextBesideIcon)
        self.header.setSizePolicy(QSizePolicy.Policy.Expanding, QSizePolicy.Policy.Fixed)
        self.header.setStyleSheet("QToolButton { font-weight: bold; text-align: left; }")
        layout = QVBoxLayout(self)
        layout.setContentsMargins(0, 0, 0, 0)
        layout.setSpacing(0)
        layout.addWidget(self.header)
        layout.addWidget(content)
        self.set_open(True)
        self.header.clicked.connect(self._clicked)  # the artist's click, not set_open

    def is_open(self) -> bool:
        return self.header.isChecked()

    def set_open(self, opened: bool) -> None:
        self.header.setChecked(opened)
        self.header.setArrowType(Qt.ArrowType.DownArrow if opened else Qt.ArrowType.RightArrow)
        self.header.setToolTip(f"{'Fold' if opened else 'Unfold'} {folding.TITLES[self.name].lower()}")
        self.content.setVisible(opened)

    def _clicked(self, opened: bool) -> None:
        self.set_open(opened)
        self.chosen.emit(self.name, opened)


class _ResizeWatch(QObject):
    """Calls ``fn`` after each resize of the widgets it is installed on."""

    def __init__(self, fn, parent: QObject) -> None:
        super().__init__(parent)
        self.fn = fn

    def eventFilter(self, watched, event) -> bool:  # noqa: N802 (Qt's API)
        if event.type() == QEvent.Type.Resize:
            self.fn()
        return False


def _slider(lo: int, hi: int, value: int) -> QSlider:
    s = QSlider(Qt.Orientation.Horizontal)
    s.setRange(lo, hi)
    s.setValue(value)
    s.setMinimumWidth(60)
    return s


def _size_box() -> QDoubleSpinBox:
    """The selected light's size in degrees (the host kit's rule: :mod:`light_size`)."""
    box = QDoubleSpinBox()
    box.setRange(*light_size.SIZE_RANGE)
    box.setDecimals(light_size.DECIMALS)
    box.setSuffix(light_size.UNIT)
    box.setKeyboardTracking(False)  # typing "0.53" sets 0.53, not 0.5 first
    box.setToolTip(light_size.SIZE_HINT)
    return box


def _intensity_box() -> QDoubleSpinBox:
    """The selected light's intensity as a number (the host kit's range, decimals and step)."""
    box = QDoubleSpinBox()
    box.setRange(*lm.INTENSITY_RANGE)
    box.setDecimals(light_editor.INTENSITY_DECIMALS)
    box.setSingleStep(light_editor.INTENSITY_STEP)
    box.setKeyboardTracking(False)  # typing "1.25" sets 1.25, not 1 first
    box.setToolTip("The selected light's intensity (Shift+wheel on the map, or the slider)")
    return box


def _form(parent: QWidget | None = None) -> QFormLayout:
    """A form whose fields go below their labels where the dock is too narrow for both on one line."""
    form = QFormLayout(parent) if parent is not None else QFormLayout()
    form.setRowWrapPolicy(QFormLayout.RowWrapPolicy.WrapLongRows)
    form.setFieldGrowthPolicy(QFormLayout.FieldGrowthPolicy.AllNonFixedFieldsGrow)
    return form


class ShadowPanel(QWidget):
    """All controls, bound to the controller's model; the actions go to the controller."""

    def __init__(self, controller, parent: QWidget | None = None, folds: FoldChoices | None = None) -> None:
        super().__init__(parent)
        self.controller = controller
        self.folds = folds if folds is not None else FoldChoices()
        self.sections: dict[str, Section] = {}
        self.model: ShadowModel = controller.model
        self._bindings: list[Binding] = []
        self._syncing = False  # the light sliders show the selected light (no edit)
        self._showing_map = False  # the map widget shows the model's map (no edit)
        self._showing_geometry = False  # the geometry controls show the model's values (no edit)
        self._build()
        self._wire()
        self.show_model(controller.model)
        self._watch = _ResizeWatch(self._fit, self)
        self.installEventFilter(self._watch)
        self.viewport.installEventFilter(self._watch)

    def sizeHint(self) -> QSize:  # noqa: N802 (Qt's API)
        """As wide as a narrow dock (added to Krita's dock column, the docker does not widen it)."""
        return QSize(PANEL_WIDTH, super().sizeHint().height())

    # -- layout ----------------------------------------------------------------------
    def _add_section(self, root: QVBoxLayout, name: str, content: QWidget) -> None:
        layout = content.layout()
        if layout is not None:
            layout.setContentsMargins(12, 0, 0, 4)  # indented under the section's title
        section = self.sections[name] = Section(name, content)
        section.chosen.connect(self._guard(lambda name, opened: self.folds.choose(name, opened)))
        root.addWidget(section)

    def _fit(self) -> None:
        """After a resize: the sections the artist has not chosen for open or folded as the dock's height has
        them (:func:`folding.open_sections`), and the map no taller than the scroll area shows."""
        states = folding.open_sections(self.height(), self.folds.chosen())
        for name, opened in states.items():
            if self.sections[name].is_open() != opened:
                self.sections[name].set_open(opened)
        cap = folding.map_height_cap(self.viewport.height(), 2 * BODY_MARGIN)
        if self.map_widget.maximumHeight() != cap:
            self.map_widget.setMaximumHeight(cap)
            self.map_widget.updateGeometry()

    def _build(self) -> None:
        outer = QVBoxLayout(self)
        outer.setContentsMargins(0, 0, 0, 0)
        # The controls scroll; Generate and the status below them stay in view.
        self.scroll = QScrollArea()
        self.scroll.setWidgetResizable(True)
        self.scroll.setFrameShape(QScrollArea.Shape.NoFrame)
        self.scroll.setMinimumHeight(folding.MAP_MIN_HEIGHT + 2 * BODY_MARGIN)  # the map in view in any dock
        self.viewport: QWidget = self.scroll.viewport()
        self.body = QWidget()
        root = QVBoxLayout(self.body)
        root.setContentsMargins(BODY_MARGIN, BODY_MARGIN, BODY_MARGIN, BODY_MARGIN)

        # The light editor first: in a short dock it (and Generate, below) is what shows.
        self.map_widget = LightMapWidget(lm.LightMap())
        root.addWidget(self.map_widget)
        form = _form()
        self.presets = QComboBox()
        self.presets.setSizeAdjustPolicy(QComboBox.SizeAdjustPolicy.AdjustToMinimumContentsLengthWithIcon)
        self.presets.setMinimumContentsLength(8)
        self.presets.addItem(CUSTOM)
        for name in lm.PRESETS:
            self.presets.addItem(preset_title(name), name)
        self.presets.setToolTip("The lights' preset (Custom: edited lights)")
        self.size_box = _size_box()
        self.intensity_box = _intensity_box()
        self.intensity = _slider(0, 300, 100)
        intensity_row = QHBoxLayout()
        intensity_row.addWidget(self.intensity_box)
        intensity_row.addWidget(self.intensity, 1)
        form.addRow("Preset", self.presets)
        form.addRow("Size", self.size_box)
        form.addRow("Intensity", intensity_row)
        root.addLayout(form)
        hint = QLabel(
            "A light casts its shadow the opposite way: right of centre, to the left; low, long. "
            "Click: add · drag: move · wheel: size · Shift+wheel: intensity · right-click / Del: remove"
        )
        hint.setWordWrap(True)
        hint.setSizePolicy(QSizePolicy.Policy.Ignored, QSizePolicy.Policy.Preferred)
        hint.setStyleSheet("color: gray; font-size: 8pt;")
        root.addWidget(hint)

        preview_box = QWidget()
        pv = QVBoxLayout(preview_box)
        self.preview = ShadowPreview()
        pv.addWidget(self.preview)
        self._add_section(root, "preview", preview_box)

        ao_box = QWidget()
        av = QVBoxLayout(ao_box)
        self.ao_preview = AOPreview()
        av.addWidget(self.ao_preview)
        legend = QLabel("Dark: the contact shadow under the object (blue). Paint to darken or lighten it.")
        legend.setWordWrap(True)
        legend.setSizePolicy(QSizePolicy.Policy.Ignored, QSizePolicy.Policy.Preferred)
        legend.setStyleSheet("color: gray; font-size: 8pt;")
        av.addWidget(legend)
        tools = QHBoxLayout()
        self.darken = QRadioButton("Darken")
        self.lighten = QRadioButton("Lighten")
        self.darken.setChecked(True)
        tools.addWidget(self.darken)
        tools.addWidget(self.lighten)
        av.addLayout(tools)
        grow_row = QHBoxLayout()
        self.grow = QPushButton("Grow")
        self.shrink = QPushButton("Shrink")
        grow_row.addWidget(self.grow)
        grow_row.addWidget(self.shrink)
        av.addLayout(grow_row)
        aform = _form()
        self.brush_size = _slider(1, 25, 5)  # radius in % of the frame
        self.brush_strength = _slider(5, 100, 50)
        self.ao_strength = _slider(0, round(100 * defaults.MAX_AO_STRENGTH), 100)
        aform.addRow("Brush size", self.brush_size)
        aform.addRow("Brush strength", self.brush_strength)
        aform.addRow("AO strength", self.ao_strength)
        av.addLayout(aform)
        arow = QHBoxLayout()
        self.ao_undo = QPushButton("Undo AO")
        self.ao_undo.setToolTip("Undo the last AO brush stroke or grow step")
        self.ao_reset = QPushButton("Reset AO")
        arow.addWidget(self.ao_undo)
        arow.addWidget(self.ao_reset)
        av.addLayout(arow)
        self._add_section(root, "ao", ao_box)

        camera_box = QWidget()
        cv = QVBoxLayout(camera_box)
        self.use_horizon = QCheckBox("Horizon at")
        self.use_horizon.setToolTip(
            "Tick to give the image's horizon and field of view; without it the engine reads the camera from the "
            "cutout's outline"
        )
        hrow = QHBoxLayout()
        self.horizon = HorizonField()
        self.horizon.setRange(*(round(b) for b in camera_rules.EDITOR_HORIZON_RANGE))
        self.horizon.setSuffix(HorizonField.unit)
        self.horizon.setMinimumWidth(80)  # narrower than its range's widest text, which few rows need
        self.horizon.setToolTip("The canvas row where the ground meets the sky (it may lie above or below the image)")
        self.from_guide = QPushButton("From guide")
        self.from_guide.setToolTip("Use the first horizontal guide as the horizon")
        hrow.addWidget(self.horizon, 1)
        hrow.addWidget(self.from_guide)
        cform = _form()
        self.fov = FovField()
        self.fov.setRange(*camera_rules.EDITOR_FOV_RANGE)
        self.fov.setDecimals(0)
        self.fov.setSuffix(FovField.unit)
        self.fov.setValue(camera_rules.DEFAULT_FOV)
        self.fov.setToolTip("The image's vertical field of view (a phone camera: about 50 degrees)")
        cform.addRow("Field of view", self.fov)
        sample = camera_rules.camera_read_note(  # the longest reading
            {"horizon": camera_rules.EDITOR_HORIZON_RANGE[0], "fov": camera_rules.EDITOR_FOV_RANGE[1]}, 0
        )
        self.camera_read = SteadyLabel([CAMERA_NOTES["unknown"], sample, CAMERA_NOTES["given"]])
        self.camera_read.setStyleSheet("color: gray;")
        cv.addWidget(self.use_horizon)
        cv.addLayout(hrow)
        cv.addLayout(cform)
        cv.addWidget(self.camera_read)
        self._add_section(root, "camera", camera_box)

        geometry_box = QWidget()
        gv = QVBoxLayout(geometry_box)
        gform = _form()
        self.lift_box = QSpinBox()
        self.lift_box.setRange(0, MAX_BOX)
        self.lift_box.setSuffix(" px")
        self.lift_box.setMinimumWidth(70)
        self.lift_box.setKeyboardTracking(False)  # typing "40" sets 40, not 4 first
        self.lift_box.setToolTip(LIFT_HINT)
        self.lift_slider = _slider(0, LIFT_SLIDER_ROWS, 0)
        self.lift_slider.setToolTip(LIFT_HINT)
        lift_row = QHBoxLayout()
        lift_row.addWidget(self.lift_box)
        lift_row.addWidget(self.lift_slider, 1)
        gform.addRow("Lift", lift_row)
        gv.addLayout(gform)
        self.thickness_label = QLabel(thickness_text(None, None))
        self.thickness_label.setWordWrap(True)
        self.thickness_label.setSizePolicy(QSizePolicy.Policy.Ignored, QSizePolicy.Policy.Preferred)
        self.thickness = _slider(0, round(100 * geometry_rules.THICKNESS_RANGE[1]), 100)
        self.thickness.setToolTip(THICKNESS_HINT + " Reset: the thickness read from the outline.")
        scale = QHBoxLayout()
        for text, align in (
            ("flat", Qt.AlignmentFlag.AlignLeft),
            ("round", None),
            ("deep", Qt.AlignmentFlag.AlignRight),
        ):
            if align is None:
                scale.addStretch(1)
                label = QLabel(text)
                scale.addWidget(label)
                scale.addStretch(1)
            else:
                label = QLabel(text)
                scale.addWidget(label)
            label.setStyleSheet("color: gray; font-size: 8pt;")
        gv.addWidget(self.thickness_label)
        gv.addWidget(self.thickness)
        gv.addLayout(scale)
        self.geometry_reset = QPushButton("Reset geometry")
        self.geometry_reset.setToolTip("On the ground (lift 0), the thickness read from the outline")
        gv.addWidget(self.geometry_reset)
        self._add_section(root, "geometry", geometry_box)

        shadow_box = QWidget()
        sf = _form(shadow_box)
        self.color_button = QPushButton()
        self.color_button.setToolTip("Shadow colour")
        self.opacity = _slider(0, 100, round(100 * defaults.OPACITY))
        sf.addRow("Colour", self.color_button)
        sf.addRow("Opacity", self.opacity)
        self._add_section(root, "shadow", shadow_box)
        root.addStretch(1)
        self.scroll.setWidget(self.body)
        outer.addWidget(self.scroll, 1)

        # The footer, short so that a short dock keeps room for the map: Live, Generate and Cancel (a cross) on
        # one row, the busy bar a thin line under it, the status.
        footer = QVBoxLayout()
        footer.setContentsMargins(4, 2, 4, 4)
        footer.setSpacing(2)
        row = QHBoxLayout()
        self.live = QCheckBox("Live")
        self.live.setToolTip("Follow the lights as they change: the preview follows a dragged light")
        self.generate = QPushButton("Generate shadow")
        self.generate.setDefault(True)
        self.cancel = QToolButton()  # a cross, not a word: the row fits a narrow dock at a large font
        self.cancel.setText("\N{MULTIPLICATION X}")
        self.cancel.setAccessibleName("Cancel")
        self.cancel.setToolTip("Cancel: stop waiting for the shadow engine (it restarts with the next Generate)")
        row.addWidget(self.live)
        row.addWidget(self.generate, 1)
        row.addWidget(self.cancel)
        footer.addLayout(row)
        self.busy = QProgressBar()
        self.busy.setRange(0, 0)  # an indeterminate busy indicator
        self.busy.setFixedHeight(5)
        self.busy.setTextVisible(False)
        busy_row = QHBoxLayout()
        busy_row.addWidget(self.busy, 1)
        for w in (self.busy, self.cancel):  # hidden while idle, keeping their place
            keep = w.sizePolicy()
            keep.setRetainSizeWhenHidden(True)
            w.setSizePolicy(keep)
            w.setVisible(False)
        footer.addLayout(busy_row)
        self.message = QLabel()
        self.message.setWordWrap(True)
        self.message.setTextInteractionFlags(Qt.TextInteractionFlag.TextSelectableByMouse)
        self.message.setSizePolicy(QSizePolicy.Policy.Ignored, QSizePolicy.Policy.Preferred)
        footer.addWidget(self.message)
        outer.addLayout(footer)

    def _wire(self) -> None:
        """The connections that do not depend on the document: actions, tools, the controller's state."""
        c, guard = self.controller, self._guard
        self.generate.clicked.connect(guard(lambda *_: c.generate()))
        self.cancel.clicked.connect(guard(lambda *_: c.cancel()))
        self.from_guide.clicked.connect(guard(lambda *_: c.horizon_from_guide()))
        self.presets.activated.connect(guard(self._choose_preset))
        self.map_widget.lightsChanged.connect(guard(self._lights_changed))
        self.map_widget.selectionChanged.connect(guard(lambda _: self._sync_light_controls()))
        self.size_box.valueChanged.connect(guard(self._size_set))
        self.intensity.valueChanged.connect(guard(self._intensity_moved))
        self.intensity_box.valueChanged.connect(guard(self._intensity_entered))
        self.ao_preview.brushed.connect(guard(self._brush))
        self.brush_size.valueChanged.connect(guard(self._brush_size))
        self.grow.clicked.connect(guard(lambda *_: self.model.grow_ao(2)))
        self.shrink.clicked.connect(guard(lambda *_: self.model.grow_ao(-2)))
        self.ao_undo.clicked.connect(guard(lambda *_: self.model.undo_ao()))
        self.ao_reset.clicked.connect(guard(lambda *_: self.model.reset_ao()))
        self.color_button.clicked.connect(guard(lambda *_: self._pick_colour()))
        self.lift_box.valueChanged.connect(guard(lambda v: self._lift_set(v, self.lift_box)))
        self.lift_slider.valueChanged.connect(guard(lambda v: self._lift_set(v, self.lift_slider)))
        self.lift_slider.sliderReleased.connect(guard(lambda: self._lift_set(self.lift_slider.value(), None)))
        self.thickness.valueChanged.connect(guard(lambda v: self._thickness_set(v, self.thickness)))
        self.thickness.sliderReleased.connect(guard(lambda: self._thickness_set(self.thickness.value(), None)))
        self.geometry_reset.clicked.connect(guard(lambda *_: self.model.reset_geometry()))
        self.preview.liftDragged.connect(guard(lambda lift, done: self.model.edit_lift(lift, False, not done)))
        for slider in (self.intensity, self.ao_strength, self.opacity):  # a drag: one undo step
            slider.sliderPressed.connect(guard(lambda: self.model.begin_stroke()))
            slider.sliderReleased.connect(guard(lambda: self.model.end_stroke()))
        bind(c, "live", self.live.setChecked, self.live.toggled, guard(lambda on: setattr(c, "live", on)))
        bind(c, "busy", guard(self._show_busy))
        c.aoChanged.connect(guard(self.ao_preview.set_images))
        c.previewed.connect(guard(self.preview.set_image))
        self.preview.resized.connect(guard(lambda w, h: setattr(c, "preview_box", (w, h))))
        c.engineReady.connect(guard(self._engine_ready))

    def show_model(self, model: ShadowModel) -> None:
        """Show (and edit) ``model``: the controller's, after it changed to another document's."""
        for binding in self._bindings:
            binding.disconnect()
        self.model, guard = model, self._guard
        if self.controller.source is None:  # another document: its image comes with its next Generate
            self.preview.clear()
        self._bindings = [
            bind(model, "light_map", guard(self._show_light_map)),
            self._bind_percent(model, "ao_strength", self.ao_strength),
            bind(
                model,
                "use_horizon",
                guard(self._show_use_horizon),
                self.use_horizon.toggled,
                guard(lambda on: setattr(model, "use_horizon", on)),
            ),
            self._bind_camera_field(model, "horizon", self.horizon),
            self._bind_camera_field(model, "fov", self.fov),
            bind(model, "camera_read", guard(lambda _: self._show_camera_fields())),
            bind(model, "color", guard(self._show_colour)),
            self._bind_percent(model, "opacity", self.opacity),
            bind(model, "status", guard(lambda status: self.show_message(*status))),
            bind(model, "ground", guard(lambda _: self._show_geometry())),
            bind(model, "lift", guard(lambda _: self._show_geometry())),
            bind(model, "thickness", guard(lambda _: self._show_geometry())),
            bind(model, "thickness_read", guard(lambda _: self._show_geometry())),
        ]

    def _bind_percent(self, model: ShadowModel, name: str, box: QSlider) -> Binding:
        """The model's fraction ``name`` (0 to 1) shown and edited in percent on the slider ``box``."""
        return bind(
            model,
            name,
            lambda v: box.setValue(round(100 * v)),
            box.valueChanged,
            self._guard(lambda v: setattr(model, name, v / 100.0)),
        )

    def _bind_camera_field(self, model: ShadowModel, name: str, box: QSpinBox | QDoubleSpinBox) -> Binding:
        """The model's camera value ``name`` edited in ``box`` (taken when its editing ends); the camera fields
        shown anew when it changes."""
        return bind(
            model,
            name,
            self._guard(lambda v: self._show_camera_fields()),
            box.editingFinished,
            self._guard(lambda: setattr(model, name, float(box.value()))),
        )

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
        self._show_preset(light_map)
        self._sync_light_controls()

    def _choose_preset(self, index: int) -> None:
        name = self.presets.itemData(index)
        if name is not None:
            self.model.light_map = lm.preset(name)

    def _show_preset(self, light_map: lm.LightMap) -> None:
        """The preset box names the preset the lights are, or says Custom."""
        for i in range(1, self.presets.count()):
            if lm.preset(self.presets.itemData(i)) == light_map:
                self.presets.setCurrentIndex(i)
                return
        self.presets.setCurrentIndex(0)

    def _lights_changed(self, live: bool, new_stroke: bool) -> None:
        if self._showing_map:
            return
        self._sync_light_controls()
        dragging = live and self.map_widget.editor.dragging  # a preview in the docker; the layer on release
        self.model.edit_light_map(self.map_widget.light_map, new_stroke, dragging)

    def _sync_light_controls(self) -> None:
        i = self.map_widget.selected
        light = self.map_widget.light_map.lights[i] if i is not None and i < len(self.map_widget.light_map) else None
        self.size_box.setEnabled(light is not None)
        self.intensity.setEnabled(light is not None)
        self.intensity_box.setEnabled(light is not None)
        if light is not None:
            self._syncing = True
            self.size_box.setPrefix(light_size.size_prefix(light))
            self.size_box.setValue(light_size.shown_size(light))
            self.size_box.setSingleStep(light_size.increments(self.size_box.value())[0])  # Page Up/Down: ten steps
            self.intensity.setValue(round(100 * light.intensity))
            self.intensity_box.setValue(light.intensity)
            self._syncing = False

    def _size_set(self, degrees: float) -> None:
        if not self._syncing:  # the widget's lightsChanged edits the model
            self.map_widget.editor.set_size(degrees)

    def _intensity_moved(self, value: int) -> None:
        if not self._syncing:
            self.map_widget.editor.set_intensity(value / 100.0, self.model.take_step())

    def _intensity_entered(self, value: float) -> None:
        """A number typed or stepped in the Intensity box: a complete edit, one undo step."""
        if not self._syncing:
            self.map_widget.editor.enter_intensity(value)

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
        self._show_camera_fields()

    def _show_camera_fields(self) -> None:
        """The fields show the given camera, else the one the model read from the outline (so that ticking the
        box starts from it), else a dash; the note below says which (in a space that does not change)."""
        m = self.model
        read = m.camera_read
        unknown = not m.use_horizon and read is None
        self.horizon.setValue(round(m.horizon))
        self.fov.setValue(m.fov)
        self.horizon.set_unknown(unknown)
        self.fov.set_unknown(unknown)
        if m.use_horizon:
            note = CAMERA_NOTES["given"]
        elif read is None:
            note = CAMERA_NOTES["unknown"]
        else:
            source = self.controller.source  # the cutout's image, whose camera the model read
            note = camera_rules.camera_read_note(read, source.height if source is not None else 0)
        self.camera_read.setText(note)

    # -- geometry --------------------------------------------------------------------------
    def _show_geometry(self) -> None:
        """The lift box and slider (their ranges: the cutout's canvas where known), the thickness slider and its
        label (the reading where none is set), the preview's handle."""
        m = self.model
        self._showing_geometry = True
        try:
            if m.ground is not None:
                height = m.ground[1][1]
                self.lift_box.setMaximum(min(MAX_BOX, round(geometry_rules.max_lift(height))))
                self.lift_slider.setMaximum(max(1, height))
            self.lift_box.setValue(round(m.lift))
            self.lift_slider.setValue(round(m.lift))
            shown = m.thickness if m.thickness is not None else m.thickness_read
            self.thickness.setValue(round(100 * (shown if shown is not None else 1.0)))
            self.thickness_label.setText(thickness_text(m.thickness, m.thickness_read))
        finally:
            self._showing_geometry = False
        self.preview.set_ground(m.ground, m.lift)

    def _lift_set(self, value: int, widget: QWidget | None) -> None:
        """The box or slider set ``value`` rows (``widget`` None: the slider's release). A slider drag is
        previewed; its release, a typed value or a step is the layer's."""
        if self._showing_geometry:
            return
        dragging = widget is self.lift_slider and self.lift_slider.isSliderDown()
        if widget is None or dragging:
            self.model.edit_lift(float(value), False, dragging)
        else:
            self.model.edit_lift(float(value), True)

    def _thickness_set(self, value: int, widget: QWidget | None) -> None:
        """The slider set ``value`` hundredths (``widget`` None: its release), as :meth:`_lift_set`."""
        if self._showing_geometry:
            return
        dragging = widget is not None and self.thickness.isSliderDown()
        self.model.edit_thickness(value / 100.0, widget is not None and not dragging, dragging)

    # -- shadow ----------------------------------------------------------------------------
    def _show_colour(self, rgb: tuple[float, float, float]) -> None:
        r, g, b = (round(255 * c) for c in rgb)
        self.color_button.setStyleSheet(f"background-color: rgb({r}, {g}, {b}); min-height: 18px;")

    def _pick_colour(self) -> None:
        r, g, b = (round(255 * c) for c in self.model.color)
        colour = QColorDialog.getColor(QColor(r, g, b), self, "Shadow colour")
        if colour.isValid():
            self.model.color = (colour.redF(), colour.greenF(), colour.blueF())
