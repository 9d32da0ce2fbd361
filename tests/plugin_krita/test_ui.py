import json
import pytest

from PyQt5.QtCore import QElapsedTimer, QEvent, QPoint, QPointF, QSettings, Qt
from PyQt5.QtGui import QMouseEvent, QWheelEvent
from PyQt5.QtTest import QTest
from PyQt5.QtWidgets import QApplication

from krita_helpers import FakeHost
from ssn_engine.host_kit.ao_edits import AoEdits
from plugin_krita.ssn_shadow.controller import ShadowController
from plugin_krita.ssn_shadow.persistence import ANNOTATION, DocumentModels
from plugin_krita.ssn_shadow.shared import light_map as lm
from plugin_krita.ssn_shadow.shared import light_editor
from plugin_krita.ssn_shadow.ui import folding, light_map_widget
from plugin_krita.ssn_shadow.ui.light_map_widget import LightMapWidget
from plugin_krita.ssn_shadow.ui.panel import FoldChoices, ShadowPanel


class NoEngine:
    """An engine that never answers (enough for UI state)."""

    def __init__(self):
        self.sent, self.params, self.buffers = [], [], []

    def request(self, cmd, buffers=None, *, on_reply=None, on_error=None, timeout=None, **params):
        self.sent.append(cmd)
        self.params.append(params)
        self.buffers.append(buffers or {})
        return len(self.sent)


def widget(qapp, light_map=None):
    w = LightMapWidget(light_map if light_map is not None else lm.LightMap())
    w.resize(400, 200)
    w.show()
    events = []
    w.lightsChanged.connect(lambda dragging, started: events.append((dragging, started)))
    return w, events


def pos(w, u, v):
    p = w.from_uv(u, v)
    return QPoint(round(p.x()), round(p.y()))


def drag_move(w, point):
    """A mouse move over ``w`` to ``point`` with the left button held (QTest's mouseMove carries no button)."""
    QApplication.sendEvent(w, QMouseEvent(QEvent.MouseMove, QPointF(point), Qt.NoButton, Qt.LeftButton, Qt.NoModifier))


def generated_panel(width, height, host=None):
    """The panel shown at ``width`` x ``height`` on a controller as after a Generate (its source read, its cutout
    at the worker), whose engine never answers: (the engine, the host, the controller, the panel)."""
    engine, host = NoEngine(), host or FakeHost()
    c = ShadowController(engine, host)
    panel = ShadowPanel(c)
    panel.resize(width, height)
    panel.show()
    QApplication.processEvents()
    c.source, c.cutout = host.read_source(host.document), "c1"
    c._cutout_geometry = (0.0, None)  # the worker's cutout has the model's lift and thickness (set at Generate)
    return engine, host, c, panel


def test_click_adds_drag_moves_right_click_deletes(qapp):
    w, events = widget(qapp)
    QTest.mouseClick(w, Qt.LeftButton, Qt.NoModifier, pos(w, 0.3, 0.5))
    assert len(w.light_map) == 1 and w.selected == 0 and events[0] == (False, True)  # a complete edit, a new step
    light = w.light_map.lights[0]
    assert abs(light.u - 0.3) < 0.01 and abs(light.v - 0.5) < 0.02

    QTest.mousePress(w, Qt.LeftButton, Qt.NoModifier, pos(w, 0.3, 0.5))
    drag_move(w, pos(w, 0.6, 0.2))
    QTest.mouseRelease(w, Qt.LeftButton, Qt.NoModifier, pos(w, 0.6, 0.2))
    light = w.light_map.lights[0]
    assert len(w.light_map) == 1 and abs(light.u - 0.6) < 0.01 and abs(light.v - 0.2) < 0.02
    assert (True, True) in events[1:]  # the first move of a drag starts a new undo step

    QTest.mouseClick(w, Qt.RightButton, Qt.NoModifier, pos(w, 0.6, 0.2))
    assert len(w.light_map) == 0


def test_a_drag_makes_the_maps_picture_at_most_every_interval_and_ends_with_the_lights_picture(qapp, monkeypatch):
    """The map's picture (pure Python on Krita's UI thread) is not made for every mouse move of a drag, which at
    the mouse's rate took CPU from the worker's previews; a pause in the drag, and its end, show the picture of
    the lights where they are."""
    made = []
    real = light_map_widget.light_map_picture.map_rgb

    def map_rgb(lights, width, height):
        made.append(lights.copy())
        return real(lights, width, height)

    monkeypatch.setattr(light_map_widget.light_map_picture, "map_rgb", map_rgb)
    w, events = widget(qapp, lm.preset("softbox"))
    QTest.qWait(10)
    light = w.light_map.lights[0]
    QTest.mousePress(w, Qt.LeftButton, Qt.NoModifier, pos(w, light.u, light.v))
    timer = QElapsedTimer()
    timer.start()
    for k in range(30):  # the mouse as fast as the event loop goes, each move drawn
        drag_move(w, pos(w, 0.3 + 0.001 * k, light.v))
        QApplication.processEvents()
    # the widget's first picture (its first paint may come late on a busy machine), the press's, one per interval
    most = timer.elapsed() // light_map_widget.PICTURE_INTERVAL_MS + 3
    assert len(made) <= min(most, 29), (len(made), timer.elapsed())
    QTest.qWait(2 * light_map_widget.PICTURE_INTERVAL_MS)  # the drag rests: the picture catches up
    assert made[-1] == w.light_map
    QTest.mouseRelease(w, Qt.LeftButton, Qt.NoModifier, pos(w, 0.31, light.v))
    QTest.qWait(10)
    assert made[-1] == w.light_map and w.picture() is not None


def wheel(w, u, v):
    centre = QPointF(pos(w, u, v))
    return QWheelEvent(
        centre,
        w.mapToGlobal(centre.toPoint()),
        QPoint(),
        QPoint(0, 120),
        Qt.NoButton,
        Qt.NoModifier,
        Qt.NoScrollPhase,
        False,
    )


def test_wheel_size_and_delete_key(qapp):
    w, events = widget(qapp, lm.preset("softbox"))
    before = w.light_map.lights[0].angle
    QApplication.sendEvent(w, wheel(w, w.light_map.lights[0].u, w.light_map.lights[0].v))
    assert w.light_map.lights[0].angle == before * 1.25
    w.setFocus()
    QTest.keyClick(w, Qt.Key_Delete)
    assert len(w.light_map) == 0


def test_the_size_box_shows_and_sets_the_selected_lights_size_in_degrees(qapp):
    c = ShadowController(NoEngine(), FakeHost())
    panel = ShadowPanel(c)
    panel.show()
    box, m = panel.size_box, c.model
    assert (box.minimum(), box.maximum(), box.decimals(), box.suffix()) == (0.1, 40.0, 2, "\N{DEGREE SIGN}")
    assert box.value() == 16.0 and box.singleStep() == 1.0  # the softbox preset
    power = m.light_map.lights[0].power
    box.setValue(0.53)  # as typed
    light = m.light_map.lights[0]
    assert light.angle == 0.53 and light.power == power  # the model's lights: the next shadow's
    assert panel.presets.currentText() == "Custom" and box.singleStep() == 0.01
    box.stepBy(1)  # an arrow click
    assert m.light_map.lights[0].angle == 0.54
    # the wheel on the map changes the size, and the box follows
    w = panel.map_widget
    QApplication.sendEvent(w, wheel(w, light.u, light.v))
    assert m.light_map.lights[0].angle == 0.68 and box.value() == 0.68  # 0.54 * 1.25, to two decimals
    # a preset: the box shows its light; an old file's Gaussian light shows the disk as wide, "about"
    panel.presets.setCurrentIndex(panel.presets.findData("sun"))
    panel.presets.activated.emit(panel.presets.currentIndex())
    assert box.value() == 0.53 and box.prefix() == ""
    m.light_map = lm.preset("two-lights")
    assert box.prefix() == "\N{ALMOST EQUAL TO}" and box.value() == round(m.light_map.lights[0].size_degrees, 2)
    assert m.light_map.lights[0].angle is None  # showing it edits nothing
    box.setValue(3.0)
    assert m.light_map.lights[0].angle == 3.0 and box.prefix() == ""
    m.light_map = lm.LightMap()
    assert not box.isEnabled()


def test_the_intensity_box_shows_and_sets_the_selected_lights_intensity(qapp):
    """A number beside the Intensity slider: the host kit's range, decimals and step; it follows the selected
    light, and a value typed in it is one complete edit (one undo step), the slider following."""
    c = ShadowController(NoEngine(), FakeHost())
    panel = ShadowPanel(c)
    panel.show()
    box, m = panel.intensity_box, c.model
    assert (box.minimum(), box.maximum()) == lm.INTENSITY_RANGE
    assert box.decimals() == light_editor.INTENSITY_DECIMALS == 2 and box.singleStep() == light_editor.INTENSITY_STEP
    assert box.value() == m.light_map.lights[0].intensity == 2.0  # the softbox preset
    edits = []
    m.edited.connect(lambda what, step: edits.append((what, step)))
    box.setValue(1.25)  # as typed (the box takes it when the typing ends)
    assert m.light_map.lights[0].intensity == 1.25 and edits == [("light_map", True)]
    assert panel.intensity.value() == 125 and panel.presets.currentText() == "Custom"
    panel.intensity.setValue(250)  # the slider: the box follows, and shows it without another edit
    assert box.value() == 2.5 and m.light_map.lights[0].intensity == 2.5 and len(edits) == 2
    # Shift+wheel on the map, and another light selected: the box shows that light's intensity
    m.light_map = lm.preset("two-lights")
    panel.map_widget.editor.select(1)
    assert box.value() == round(m.light_map.lights[1].intensity, 2)
    m.light_map = lm.LightMap()
    assert not box.isEnabled()


def test_the_folding_rule():
    """Without Qt: which sections start open for a dock's height, the artist's choice first; the map's cap."""
    short, tall = folding.SHORT_PANEL - 1, folding.SHORT_PANEL
    assert folding.open_sections(161, {}) == dict.fromkeys(folding.SECTIONS, False)  # Krita's 262 x 180 docker
    assert folding.open_sections(short, {}) == dict.fromkeys(folding.SECTIONS, False)
    assert folding.open_sections(tall, {}) == dict.fromkeys(folding.SECTIONS, True)
    chosen = folding.open_sections(161, {"ao": True, "camera": False})
    assert chosen == {"preview": False, "ao": True, "camera": False, "geometry": False, "shadow": False}
    assert folding.open_sections(900, {"camera": False})["camera"] is False
    assert folding.map_height_cap(91, 8) == 83 and folding.map_height_cap(30, 8) == folding.MAP_MIN_HEIGHT


def test_a_short_dock_shows_the_map_and_generate_and_folds_the_rest(qapp, tmp_path):
    """Krita's default workspace on a 1366 x 768 screen stacks the docker about 180 px tall: the map (all of it)
    and Generate are in view without scrolling, the other sections folded; an unfolded one stays so."""
    folds = FoldChoices(QSettings(str(tmp_path / "folds.ini"), QSettings.Format.IniFormat))
    engine, host, c, panel = generated_panel(262, 161)  # the docker's 180 px less its title bar
    panel.folds = folds
    panel.resize(262, 160)
    QApplication.processEvents()
    viewport = panel.scroll.viewport()
    map_box = panel.map_widget
    top, bottom = map_box.mapTo(viewport, QPoint(0, 0)), map_box.mapTo(viewport, map_box.rect().bottomRight())
    assert viewport.rect().contains(top) and viewport.rect().contains(bottom), (top, bottom, viewport.rect())
    assert map_box.height() >= folding.MAP_MIN_HEIGHT and panel.scroll.verticalScrollBar().value() == 0
    generate = panel.generate.mapTo(panel, panel.generate.rect().bottomRight())
    assert panel.rect().contains(generate) and not panel.generate.visibleRegion().isEmpty()
    assert not any(section.is_open() for section in panel.sections.values())
    assert not panel.preview.isVisible() and not panel.ao_preview.isVisible()
    panel.sections["ao"].header.click()  # the artist unfolds the AO
    assert panel.ao_preview.isVisible() and folds.chosen() == {"ao": True}
    # the next Krita (the choice read back from the settings' file), in the same short dock
    again = ShadowPanel(
        ShadowController(NoEngine(), FakeHost()),
        folds=FoldChoices(QSettings(str(tmp_path / "folds.ini"), QSettings.Format.IniFormat)),
    )
    again.resize(262, 160)
    again.show()
    QApplication.processEvents()
    assert {n: s.is_open() for n, s in again.sections.items()} == {
        "preview": False,
        "ao": True,
        "camera": False,
        "geometry": False,
        "shadow": False,
    }
    again.resize(262, 900)  # a tall dock: the sections the artist left alone open
    QApplication.processEvents()
    assert (
        all(s.is_open() for s in again.sections.values()) and again.map_widget.height() == again.map_widget.width() // 2
    )


def test_ao_edits_list():
    e = AoEdits()
    e.brush(0.5, 0.9, 0.05, -0.5, True)
    e.brush(0.52, 0.9, 0.05, -0.5, False)
    e.grow(2)
    ops = e.to_list(1.5)
    assert [o["op"] for o in ops] == ["brush", "brush", "grow", "strength"]
    assert e.undo() and [o["op"] for o in e.to_list(1.5)] == ["brush", "brush", "strength"]
    assert e.undo() and e.to_list(1.5) == [{"op": "strength", "value": 1.5}]
    assert not e.undo() and e.to_list() == []


def test_panel_state(qapp):
    engine = NoEngine()
    c = ShadowController(engine, FakeHost())
    panel = ShadowPanel(c)
    panel.show()
    assert not panel.busy.isVisible()
    assert "press Generate" in panel.message.text()
    panel.generate.click()
    assert panel.busy.isVisible() and panel.cancel.isVisible() and engine.sent == ["set_cutout"]
    c._fail("the shadow engine exited with code 1; it will restart on the next request.")
    assert not panel.busy.isVisible() and not panel.cancel.isVisible() and "restart" in panel.message.text()

    m = c.model
    assert panel.presets.currentText() == "Softbox"  # the default lights: the preset's name for people
    panel.presets.setCurrentIndex(panel.presets.findData("two-lights"))
    panel.presets.activated.emit(panel.presets.currentIndex())
    assert len(m.light_map) == 2 and panel.map_widget.light_map == m.light_map
    assert panel.map_widget.light_map is not m.light_map  # the model keeps its own copy
    assert panel.presets.currentText() == "Two lights"
    assert panel.presets.itemText(panel.presets.findData("low-sun-left")) == "Low sun, left"

    panel.live.setChecked(False)
    assert c.live is False
    c.live = True
    assert panel.live.isChecked()
    panel.opacity.setValue(40)
    assert m.opacity == 0.4
    m.opacity = 0.7  # the model changed (e.g. loaded): the slider follows
    assert panel.opacity.value() == 70
    m.color = (0.1, 0.1, 0.3)
    assert "rgb(26, 26, 76)" in panel.color_button.styleSheet()
    panel.intensity.setValue(250)
    assert m.light_map.lights[panel.map_widget.selected].intensity == 2.5
    assert panel.presets.currentText() == "Custom"  # an edit: no preset's lights any more
    m.light_map = lm.preset("low-sun-right")
    assert panel.presets.currentText() == "Low sun, right"
    panel.ao_strength.setValue(150)
    assert m.ao_strength == 1.5 and m.ao_edit_list() == [{"op": "strength", "value": 1.5}]
    panel.grow.click()
    panel.ao_undo.click()
    panel.shrink.click()
    assert m.ao_edits.steps == [[{"op": "grow", "pixels": -2}]]
    panel.ao_reset.click()
    assert m.ao_edit_list() == [] and panel.ao_strength.value() == 100


def test_a_drag_on_the_map_previews_and_the_release_renders_the_layer(qapp):
    engine, host, c, panel = generated_panel(360, 900)
    w = panel.map_widget
    light = w.light_map.lights[0]
    QTest.mousePress(w, Qt.LeftButton, Qt.NoModifier, pos(w, light.u, light.v))
    for k in range(1, 4):
        drag_move(w, pos(w, light.u + 0.05 * k, light.v))
    assert engine.sent == ["preview"]  # one in flight (this engine never answers), no layer render
    assert engine.params[0]["read_horizon"] is True and "horizon" not in engine.params[0]  # no camera set
    QTest.mouseRelease(w, Qt.LeftButton, Qt.NoModifier, pos(w, light.u + 0.15, light.v))
    assert engine.sent[1:] == ["set_cutout"]  # the layer's render (the cutout first: its key is new here)
    assert c.model.light_map == w.light_map

    assert panel.preview.isVisible() and panel.preview.image is None  # its place is kept before any preview
    c.previewed.emit(bytes([90, 90, 90]) * (200 * 160), 200, 160)
    assert panel.preview.isVisible() and panel.preview.image.size().width() == 200
    assert panel.preview.heightForWidth(240) == 150 and panel.preview.heightForWidth(400) == 200


def test_a_drag_previews_at_the_size_the_docker_draws_the_preview(qapp):
    """The preview's image is asked for as large as the docker shows it (in device pixels), not larger: the
    worker renders, and traces a small light on, each of its pixels."""
    engine, host, c, panel = generated_panel(300, 900, FakeHost(w=2000, h=1500))
    w = panel.map_widget
    light = w.light_map.lights[0]
    QTest.mousePress(w, Qt.LeftButton, Qt.NoModifier, pos(w, light.u, light.v))
    target = pos(w, light.u + 0.05, light.v)
    drag_move(w, target)
    assert engine.sent == ["preview"]
    height, width = engine.buffers[0]["background"].shape[:2]
    ratio = panel.preview.devicePixelRatioF()
    box = (panel.preview.width() * ratio, panel.preview.height() * ratio)
    assert width <= box[0] + 1 and height <= box[1] + 1  # drawn without being scaled down
    assert max(width - box[0], height - box[1]) > -1.5  # filling the box's width or height
    assert (width, height) != (320, 240)  # the size before, as large as the preview could be
    QTest.mouseRelease(w, Qt.LeftButton, Qt.NoModifier, target)


def test_the_first_preview_of_a_drag_moves_nothing_under_the_mouse(qapp):
    """The first light drag after Generate: the preview's first image comes mid-drag; the map stays where it
    is, and the light ends where the mouse was released."""
    engine, host, c, panel = generated_panel(300, 700)
    w = panel.map_widget
    light = w.light_map.lights[0]
    at_press = w.mapTo(panel, QPoint(0, 0))
    QTest.mousePress(w, Qt.LeftButton, Qt.NoModifier, pos(w, light.u, light.v))
    target = pos(w, light.u + 0.1, light.v + 0.1)
    drag_move(w, target)
    c.previewed.emit(bytes([90, 90, 90]) * (320 * 240), 320, 240)  # the drag's first preview
    QApplication.processEvents()
    assert w.mapTo(panel, QPoint(0, 0)) == at_press
    drag_move(w, target)
    QTest.mouseRelease(w, Qt.LeftButton, Qt.NoModifier, target)
    QApplication.processEvents()
    assert w.mapTo(panel, QPoint(0, 0)) == at_press
    moved = c.model.light_map.lights[0]
    assert abs(moved.u - (light.u + 0.1)) < 0.01 and abs(moved.v - (light.v + 0.1)) < 0.02


def test_the_panel_fits_a_narrow_dock(qapp):
    """Krita's default dock is 400 px wide (measured in Krita 5.1.5 with a fresh profile under a 1366 x 768
    screen); with a vertical scroll bar and a larger font than this test's it leaves less: the controls fit
    260 px, the map and previews scaled to it."""
    c = ShadowController(NoEngine(), FakeHost())
    panel = ShadowPanel(c)
    assert panel.body.minimumSizeHint().width() <= 260
    assert panel.minimumSizeHint().width() <= 260 + panel.scroll.verticalScrollBar().sizeHint().width()  # the footer
    panel.resize(260 + panel.scroll.verticalScrollBar().sizeHint().width(), 600)
    panel.show()
    QApplication.processEvents()
    assert not panel.scroll.horizontalScrollBar().isVisible()
    assert panel.map_widget.width() <= 260 and panel.presets.width() <= 260


def test_ui_errors_are_shown_not_raised(qapp):
    c = ShadowController(NoEngine(), FakeHost())
    panel = ShadowPanel(c)

    def boom():
        raise RuntimeError("kaput")

    c.generate = boom
    panel.generate.clicked.disconnect()
    panel.generate.clicked.connect(panel._guard(lambda *_: c.generate()))
    panel.generate.click()
    assert "kaput" in panel.message.text()


def test_horizon_from_guide(qapp):
    host = FakeHost()
    c = ShadowController(NoEngine(), host)
    panel = ShadowPanel(c)
    m = c.model
    assert not panel.use_horizon.isChecked() and not panel.horizon.isEnabled() and m.camera is None
    panel.from_guide.click()  # no guide yet: says how to add one, changes nothing
    assert "horizontal guide" in panel.message.text() and m.camera is None
    host.document.guides = [412.6]
    panel.from_guide.click()
    assert m.camera == {"horizon": 413.0, "fov": 45.0} and panel.use_horizon.isChecked()
    assert panel.horizon.value() == 413 and panel.horizon.isEnabled()
    panel.fov.setValue(60)
    panel.fov.editingFinished.emit()
    assert m.camera == {"horizon": 413.0, "fov": 60.0}
    panel.use_horizon.setChecked(False)
    assert m.camera is None and not panel.fov.isEnabled()


def test_the_camera_read_from_the_outline_is_shown_and_ticking_starts_from_it(qapp):
    """Without a horizon of the image's own, the docker shows the camera the model read (disabled fields and a
    note); ticking the box sends that camera. Before any camera is known the fields show a dash, not a value."""
    c = ShadowController(NoEngine(), FakeHost())
    panel = ShadowPanel(c)
    m = c.model
    edits = []
    m.edited.connect(lambda what, step: edits.append(what))
    assert panel.horizon.text() == "\u2014" and panel.fov.text() == "\u2014"  # not "0 px" and "45°"
    assert "At Generate" in panel.camera_read.text()
    m.report_camera_read({"horizon": 412.4, "fov": 47.2})
    assert not panel.use_horizon.isChecked() and not panel.horizon.isEnabled() and m.camera is None
    assert panel.horizon.value() == 412 and panel.fov.value() == 47 and not edits  # shown, not an edit
    assert panel.horizon.text() == "412 px" and panel.fov.text() == "47°"
    assert "row 412" in panel.camera_read.text()
    panel.use_horizon.setChecked(True)
    assert m.camera == {"horizon": 412.0, "fov": 47.0} and "Given" in panel.camera_read.text() and edits == ["camera"]
    m.report_camera_read(None)  # the cutout analysed with that camera: nothing read
    assert panel.horizon.value() == 412 and panel.horizon.text() == "412 px"


def test_ticking_the_horizon_box_moves_nothing(qapp):
    """Ticking "The image's horizon is at" changes the note under the fields, not the layout: the controls
    below stay under the mouse."""
    c = ShadowController(NoEngine(), FakeHost())
    panel = ShadowPanel(c)
    panel.resize(280, 900)
    panel.show()
    c.model.report_camera_read({"horizon": 412.4, "fov": 47.2})
    QApplication.processEvents()
    below = [panel.color_button, panel.opacity, panel.fov]

    def places():
        return [w.mapTo(panel.body, QPoint(0, 0)) for w in below] + [panel.body.height()]

    before = places()
    for tick in (True, False, True):
        panel.use_horizon.setChecked(tick)
        QApplication.processEvents()
        assert places() == before, tick


def test_the_panel_shows_the_active_documents_model(qapp):
    """Each document has its own settings: the panel follows the controller to another document's model and
    back, and an edit reaches only the model shown."""
    from krita_helpers import FakeDocument

    host = FakeHost()
    models = DocumentModels(host)
    first, other = host.document, FakeDocument("b.kra")
    c = ShadowController(NoEngine(), host, models.model_for(first))
    panel = ShadowPanel(c)
    host.document.guides = [300.0]
    panel.from_guide.click()
    panel.opacity.setValue(30)
    c.set_model(models.model_for(other))
    panel.show_model(c.model)
    assert not panel.use_horizon.isChecked() and panel.opacity.value() == 85  # the other's defaults
    panel.opacity.setValue(55)
    c.set_model(models.model_for(first))
    panel.show_model(c.model)
    assert panel.use_horizon.isChecked() and panel.horizon.value() == 300 and panel.opacity.value() == 30
    assert models.model_for(other).opacity == 0.55 and c.model is models.model_for(first)


def test_ao_preview_zooms_on_the_cutout_and_stretches_the_occlusion(qapp):
    """Issue #14, item 7: the preview shows the cutout and its contact shadow, not a pale whole frame."""
    from plugin_krita.ssn_shadow.ui.ao_preview import AOPreview, contrast_table

    n = 64
    mask = bytearray(n * n)
    for y in range(20, 44):
        mask[y * n + 28 : y * n + 36] = b"\xff" * 8
    ao = bytearray(b"\xff" * (n * n))
    ao[44 * n + 24 : 44 * n + 40] = b"\xe6" * 16  # a faint contact shadow (AO 0.9) under the cutout
    preview = AOPreview()
    preview.resize(200, 200)
    preview.set_images(bytes(ao), bytes(mask), n)
    left, top, size = preview.view
    assert size < 0.75 and left <= 28 / n and left + size >= 36 / n and top <= 20 / n and top + size >= 44 / n
    assert contrast_table(bytes(ao))[0xE6] < 0xA0  # AO 0.9 (a pale 230) shown mid-grey: 4 times the contrast
    ao[10 * n + 5] = 0x60  # the darkest contact shadow: occlusion 159
    table = contrast_table(bytes(ao))
    assert table[0x60] < 0x20 and table[0xF6] == 0xFF  # faint occlusion (9) far away: white, no grey swirls
    x, y = preview.to_frame(preview.frame_rect().center())
    assert abs(x - (left + size / 2)) < 1e-6 and abs(y - (top + size / 2)) < 1e-6
    dabs = []
    preview.brushed.connect(lambda bx, by, started: dabs.append((bx, by)))
    QTest.mousePress(preview, Qt.LeftButton, pos=preview.frame_rect().center().toPoint())
    assert dabs and abs(dabs[0][0] - x) < 0.02
    ao[44 * n + 24] = 0xC0  # an AO edit: same cutout, the view stays
    preview.set_images(bytes(ao), bytes(mask), n)
    assert preview.view == (left, top, size)


def test_ao_edits_stay_with_their_cutout(qapp):
    """A Generate from another layer starts without the AO edits painted on the last one (saved so)."""
    host = FakeHost()
    c = ShadowController(NoEngine(), host, DocumentModels(host).model_for(host.document))
    c.model.grow_ao(2)
    c.model.ao_strength = 2.0
    c.generate()  # the first source: the edits (e.g. loaded with the image) apply to it
    assert c.model.ao_edit_list() == [{"op": "grow", "pixels": 2}, {"op": "strength", "value": 2.0}]
    c.source = host.read_source(host.document)
    c.source.node_id = "another-layer"
    c._renders.clear()
    c.generate()
    assert c.model.ao_edit_list() == [] and c.model.ao_strength == 1.0
    assert json.loads(host.document.annotations[ANNOTATION][1])["ao_edits"] == {"steps": [], "strength": 1.0}


def test_generate_and_the_status_stay_in_view_while_the_controls_scroll(qapp):
    """In a short dock the controls scroll; Generate and the status line stay where they are, in view."""
    c = ShadowController(NoEngine(), FakeHost())
    panel = ShadowPanel(c)
    panel.resize(300, 420)
    panel.show()
    QApplication.processEvents()
    panel.sections["camera"].set_open(True)  # a short dock folds the sections: one open, the controls scroll
    QApplication.processEvents()
    bar = panel.scroll.verticalScrollBar()
    assert bar.maximum() > 0  # the controls scroll
    places = []
    for value in (0, bar.maximum() // 2, bar.maximum()):
        bar.setValue(value)
        QApplication.processEvents()
        for w in (panel.generate, panel.message):
            assert not w.visibleRegion().isEmpty()
        places.append((panel.generate.mapTo(panel, QPoint(0, 0)), panel.message.mapTo(panel, QPoint(0, 0))))
    assert places[0] == places[1] == places[2]


def test_the_geometry_section_sets_the_lift_and_thickness_and_the_previews_handle_drags_the_lift(qapp):
    """The Geometry section: a lift box and slider (pixels), a thickness slider that shows the reading until it is
    moved ("Thickness: read 0.29"), Reset back to the ground and the reading; in the preview a bar under the
    object that a vertical drag moves: the lift in canvas rows (preview rows over the preview's scale),
    previewed while dragging, the layer's render at the release."""
    from plugin_krita.ssn_shadow.ui.shadow_preview import handle_row

    class GeometryEngine(NoEngine):
        """Answers set_geometry at once (the rest never)."""

        def request(self, cmd, buffers=None, *, on_reply=None, on_error=None, timeout=None, **params):
            n = super().request(cmd, buffers, on_reply=on_reply, on_error=on_error, timeout=timeout, **params)
            if cmd == "set_geometry":
                on_reply({**params, "thickness_read": 0.29}, {})
            return n

    host, engine = FakeHost(w=400, h=400), GeometryEngine()
    c = ShadowController(engine, host)
    panel = ShadowPanel(c)
    panel.resize(360, 1400)
    panel.show()
    QApplication.processEvents()
    c.source, c.cutout = host.read_source(host.document), "c1"  # as after a Generate
    c._cutout_key, c._cutout_geometry = c.source.key, (0.0, None)
    m = c.model
    assert "geometry" in panel.sections and panel.sections["geometry"].is_open()
    assert panel.thickness_label.text() == "Thickness: read from the outline"
    m.report_ground([160, 60, 240, 220], (400, 400), 210)  # its lift counts from row 210: a soft edge below
    m.report_geometry({"lift": 0.0, "thickness": None, "thickness_read": 0.29})
    assert panel.thickness_label.text() == "Thickness: read 0.29" and panel.thickness.value() == 29
    assert panel.lift_box.maximum() == 8000 and panel.lift_slider.maximum() == 400  # 20 canvas heights; one

    panel.lift_box.setValue(40)  # typed (the box takes it when typing ends) or stepped
    assert m.lift == 40.0 and panel.lift_slider.value() == 40 and engine.sent == ["set_geometry", "render"]
    c._renders.clear()  # (this engine renders nothing)
    panel.thickness.setValue(150)
    c._renders.clear()
    assert m.thickness == 1.5 and panel.thickness_label.text() == "Thickness: 1.50"
    panel.geometry_reset.click()
    assert (m.lift, m.thickness) == (0.0, None) and panel.lift_box.value() == 0
    c._renders.clear()
    assert panel.thickness_label.text() == "Thickness: read 0.29" and panel.thickness.value() == 29

    c.previewed.emit(bytes([90, 90, 90]) * (200 * 200), 200, 200)  # the 400 x 400 image at half its size
    preview = panel.preview
    rect, handle = preview.image_rect(), preview.handle_pos()
    scale = rect.height() / 400  # preview pixels a canvas row
    assert handle.y() == pytest.approx(rect.top() + handle_row(210, 0) * scale)
    engine.sent.clear()
    start = QPoint(round(handle.x()), round(handle.y()))
    QTest.mousePress(preview, Qt.LeftButton, Qt.NoModifier, start)
    for dy in (10, 20, 30):
        drag_move(preview, start + QPoint(0, dy))
    assert m.dragging("geometry") and m.lift == pytest.approx(round((start.y() + 30 - rect.top()) / scale - 211))
    assert m.lift > 30 / scale - 2 and engine.sent[:2] == ["set_geometry", "preview"]  # previewed, no layer
    QTest.mouseRelease(preview, Qt.LeftButton, Qt.NoModifier, start + QPoint(0, 30))
    assert not m.dragging("geometry") and engine.sent[-1] == "render"  # the layer's, at the release
    assert panel.lift_box.value() == round(m.lift) and preview.handle_pos().y() > handle.y() + 25


def test_the_lift_handle_is_where_its_drag_puts_it():
    from plugin_krita.ssn_shadow.ui.shadow_preview import handle_row, lift_at

    row = 210  # the row the lift counts from
    for lift in (0.0, 12.0, 130.0):
        y = 5 + handle_row(row, lift) / 2.0  # drawn from row 5 of the widget at half size
        assert lift_at(y, 5, 2.0, row) == lift
    assert lift_at(0, 5, 2.0, row) == 0.0  # above the object's foot: on the ground
