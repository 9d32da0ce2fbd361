from PyQt5.QtCore import QEvent, QPoint, QPointF, Qt
from PyQt5.QtGui import QMouseEvent, QWheelEvent
from PyQt5.QtTest import QTest
from PyQt5.QtWidgets import QApplication

from krita_helpers import FakeHost
from ssn_engine.host_kit.ao_edits import AoEdits
from plugin_krita.ssn_shadow.controller import ShadowController
from plugin_krita.ssn_shadow.shared import light_map as lm
from plugin_krita.ssn_shadow.ui.light_map_widget import LightMapWidget, slider_to_softness, softness_to_slider
from plugin_krita.ssn_shadow.ui.panel import ShadowPanel


class NoEngine:
    """An engine that never answers (enough for UI state)."""

    def __init__(self):
        self.sent, self.params = [], []

    def request(self, cmd, buffers=None, *, on_reply=None, on_error=None, timeout=None, **params):
        self.sent.append(cmd)
        self.params.append(params)
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


def test_click_adds_drag_moves_right_click_deletes(qapp):
    w, events = widget(qapp)
    QTest.mouseClick(w, Qt.LeftButton, Qt.NoModifier, pos(w, 0.3, 0.5))
    assert len(w.light_map) == 1 and w.selected == 0 and events[0] == (False, True)  # a complete edit, a new step
    light = w.light_map.lights[0]
    assert abs(light.u - 0.3) < 0.01 and abs(light.v - 0.5) < 0.02

    QTest.mousePress(w, Qt.LeftButton, Qt.NoModifier, pos(w, 0.3, 0.5))
    move = QMouseEvent(QEvent.MouseMove, QPointF(pos(w, 0.6, 0.2)), Qt.NoButton, Qt.LeftButton, Qt.NoModifier)
    QApplication.sendEvent(w, move)
    QTest.mouseRelease(w, Qt.LeftButton, Qt.NoModifier, pos(w, 0.6, 0.2))
    light = w.light_map.lights[0]
    assert len(w.light_map) == 1 and abs(light.u - 0.6) < 0.01 and abs(light.v - 0.2) < 0.02
    assert (True, True) in events[1:]  # the first move of a drag starts a new undo step

    QTest.mouseClick(w, Qt.RightButton, Qt.NoModifier, pos(w, 0.6, 0.2))
    assert len(w.light_map) == 0


def test_wheel_softness_and_delete_key(qapp):
    w, events = widget(qapp, lm.preset("softbox"))
    before = w.light_map.lights[0].softness
    centre = QPointF(pos(w, w.light_map.lights[0].u, w.light_map.lights[0].v))
    ev = QWheelEvent(
        centre,
        w.mapToGlobal(centre.toPoint()),
        QPoint(),
        QPoint(0, 120),
        Qt.NoButton,
        Qt.NoModifier,
        Qt.NoScrollPhase,
        False,
    )
    QApplication.sendEvent(w, ev)
    assert w.light_map.lights[0].softness > before
    w.setFocus()
    QTest.keyClick(w, Qt.Key_Delete)
    assert len(w.light_map) == 0


def test_softness_slider_round_trip():
    for s in (1e-4, 0.002, 0.01, 0.1):
        assert abs(slider_to_softness(softness_to_slider(s)) / s - 1) < 0.05


def test_ao_edits_list():
    e = AoEdits()
    e.brush(0.5, 0.9, 0.05, -0.5, True)
    e.brush(0.52, 0.9, 0.05, -0.5, False)
    e.grow(2)
    e.strength = 1.5
    ops = e.to_list()
    assert [o["op"] for o in ops] == ["brush", "brush", "grow", "strength"]
    assert e.undo() and [o["op"] for o in e.to_list()] == ["brush", "brush", "strength"]
    assert e.undo() and e.to_list() == [{"op": "strength", "value": 1.5}]
    e.reset()
    assert e.to_list() == [] and not e.undo()


def test_panel_state(qapp):
    engine = NoEngine()
    c = ShadowController(engine, FakeHost())
    panel = ShadowPanel(c)
    panel.show()
    assert not panel.busy.isVisible()
    panel.generate.click()
    assert panel.busy.isVisible() and panel.cancel.isVisible() and engine.sent == ["set_cutout"]
    c._fail("the shadow engine exited with code 1; it will restart on the next request.")
    assert not panel.busy.isVisible() and not panel.cancel.isVisible() and "restart" in panel.message.text()

    panel.presets.setCurrentIndex(panel.presets.findText("two-lights"))
    panel.presets.activated.emit(panel.presets.currentIndex())
    assert len(c.light_map) == 2 and panel.map_widget.light_map == c.light_map
    assert panel.map_widget.light_map is not c.light_map  # the controller keeps its own copy

    panel.live.setChecked(False)
    assert c.live is False
    panel.opacity.setValue(40)
    assert c.opacity == 0.4
    panel.set_colour((0.1, 0.1, 0.3))
    assert c.color == (0.1, 0.1, 0.3)
    panel.intensity.setValue(250)
    assert c.light_map.lights[panel.map_widget.selected].intensity == 2.5


def test_a_drag_on_the_map_previews_and_the_release_renders_the_layer(qapp):
    engine = NoEngine()
    host = FakeHost()
    c = ShadowController(engine, host)
    panel = ShadowPanel(c)
    panel.resize(360, 900)
    panel.show()
    c.source, c.cutout = host.read_source(host.document), "c1"  # as after a Generate
    w = panel.map_widget
    light = w.light_map.lights[0]
    QTest.mousePress(w, Qt.LeftButton, Qt.NoModifier, pos(w, light.u, light.v))
    for k in range(1, 4):
        target = QPointF(pos(w, light.u + 0.05 * k, light.v))
        QApplication.sendEvent(w, QMouseEvent(QEvent.MouseMove, target, Qt.NoButton, Qt.LeftButton, Qt.NoModifier))
    assert engine.sent == ["preview"]  # one in flight (this engine never answers), no layer render
    assert engine.params[0]["read_horizon"] is True and "horizon" not in engine.params[0]  # no camera set
    QTest.mouseRelease(w, Qt.LeftButton, Qt.NoModifier, pos(w, light.u + 0.15, light.v))
    assert engine.sent[1:] == ["set_cutout"]  # the layer's render (the cutout first: its key is new here)
    assert c.light_map == w.light_map

    assert not panel.drag_preview.isVisible()
    c.previewed.emit(bytes([90, 90, 90]) * (200 * 160), 200, 160)
    assert panel.drag_preview.isVisible() and panel.drag_preview.image.size().width() == 200
    assert panel.drag_preview.heightForWidth(250) == 200 and panel.drag_preview.heightForWidth(400) == 220


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


def test_horizon_from_guide_is_remembered_per_document(qapp):
    from krita_helpers import FakeDocument

    host = FakeHost()
    c = ShadowController(NoEngine(), host)
    panel = ShadowPanel(c)
    assert not panel.use_horizon.isChecked() and not panel.horizon.isEnabled() and c.camera is None
    panel.from_guide.click()  # no guide yet: says how to add one, changes nothing
    assert "horizontal guide" in panel.message.text() and c.camera is None
    host.document.guides = [412.6]
    panel.from_guide.click()
    assert c.camera == {"horizon": 413.0, "fov": 45.0} and panel.use_horizon.isChecked()
    panel.fov.setValue(60)
    panel.fov.editingFinished.emit()
    assert c.camera == {"horizon": 413.0, "fov": 60.0}

    first, other = host.document, FakeDocument("b.kra")
    host.document = other
    panel.document_changed(other)  # another document: its own (no) camera
    assert c.camera is None and not panel.use_horizon.isChecked()
    host.document = first
    panel.document_changed(first)
    assert c.camera == {"horizon": 413.0, "fov": 60.0} and panel.horizon.value() == 413
    panel.use_horizon.setChecked(False)
    assert c.camera is None and c.camera_for(first) is None


def test_the_camera_read_from_the_outline_is_shown_and_ticking_starts_from_it(qapp):
    """Without a horizon of the image's own, the docker shows the camera the model read (disabled fields and a
    line of text); ticking the box sends that camera, and the line goes away."""
    c = ShadowController(NoEngine(), FakeHost())
    panel = ShadowPanel(c)
    assert panel.camera_read.isHidden()
    c.cameraRead.emit({"horizon": 412.4, "fov": 47.2})
    assert not panel.use_horizon.isChecked() and not panel.horizon.isEnabled() and c.camera is None
    assert panel.horizon.value() == 412 and panel.fov.value() == 47
    assert not panel.camera_read.isHidden() and "row 412" in panel.camera_read.text()
    panel.use_horizon.setChecked(True)
    assert c.camera == {"horizon": 412.0, "fov": 47.0} and panel.camera_read.isHidden()
    c.cameraRead.emit(None)  # the cutout analysed with that camera: nothing read
    assert panel.camera_read.isHidden() and panel.horizon.value() == 412


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
    x, y = preview.to_frame(preview.frame_rect().center())
    assert abs(x - (left + size / 2)) < 1e-6 and abs(y - (top + size / 2)) < 1e-6
    dabs = []
    preview.brushed.connect(lambda bx, by, started: dabs.append((bx, by)))
    QTest.mousePress(preview, Qt.LeftButton, pos=preview.frame_rect().center().toPoint())
    assert dabs and abs(dabs[0][0] - x) < 0.02
    ao[44 * n + 24] = 0xC0  # an AO edit: same cutout, the view stays
    preview.set_images(bytes(ao), bytes(mask), n)
    assert preview.view == (left, top, size)
