import numpy as np
import pytest
from krita_helpers import FakeHost, cutout_alpha, wait_until, worker_command
from PyQt5.QtCore import QEventLoop, QTimer
from plugin_krita.ssn_shadow.controller import PREVIEW_SIDE, ShadowController, preview_side
from plugin_krita.ssn_shadow.engine import EngineProcess
from ssn_engine.host_kit.engine_config import EngineConfig


def make(host, command=worker_command):
    engine = EngineProcess(command)
    c = ShadowController(engine, host)
    messages, aos = [], []
    c.model.status_changed.connect(messages.append)
    c.aoChanged.connect(lambda ao, mask, n: aos.append(n))
    return c, engine, messages, aos


def moved(c, u, v, new_step, dragging=False):
    """The editor moved the first light to (u, v)."""
    light_map = c.model.light_map.copy()
    light_map.move(0, u, v)
    c.model.edit_light_map(light_map, new_step, dragging)


def test_the_layer_mode_follows_the_shadow_colour(qapp):
    """A black shadow is written as a Normal layer (the same composite, faster in Krita), a coloured one as a
    Multiply layer: in the mode of the colour it was rendered with, even if the colour changes meanwhile."""
    host = FakeHost()
    c, engine, messages, _ = make(host)
    try:
        c.generate()
        assert wait_until(lambda: not c.busy and len(host.writes) == 1), messages
        c.live = False  # the colour changes render only with Generate
        c.model.color = (0.3, 0.1, 0.6)
        c.generate()
        c.model.color = (0.0, 0.0, 0.0)
        assert wait_until(lambda: not c.busy and len(host.writes) == 2), messages
        c.generate()
        assert wait_until(lambda: not c.busy and len(host.writes) == 3), messages
        assert host.blends == ["normal", "multiply", "normal"]
    finally:
        engine.stop()


def test_generate_then_live_drag(qapp):
    host = FakeHost()
    c, engine, messages, aos = make(host)
    busy = []
    c.busy_changed.connect(busy.append)
    try:
        c.generate()
        assert c.busy
        assert wait_until(lambda: not c.busy and host.writes), messages
        rect, nbytes, new_step = host.writes[0]
        assert new_step and rect[2] > 0 and nbytes == rect[2] * rect[3] * 4
        assert busy[:2] == [True, False] and wait_until(lambda: aos)
        cutout = c.cutout

        c.generate()  # same alpha: the engine's cutout (and its AO) is reused
        assert wait_until(lambda: not c.busy and len(host.writes) == 2)
        assert c.cutout == cutout and host.writes[1][2]

        for i in range(30):  # a fast slider drag: requests coalesce, only the first is an undo step
            moved(c, 0.2 + 0.01 * i, 0.6, i == 0)
        assert wait_until(lambda: not c.busy)
        live = host.writes[2:]
        assert 1 <= len(live) < 30
        assert live[0][2] and not any(w[2] for w in live[1:])
        assert host.reads == 2  # live updates do not read the image again
        assert not [m for m in messages if m[0] == "error"]

        c.model.ao_strength = 2.0
        assert wait_until(lambda: not c.busy and len(aos) >= 2)
        assert host.writes[-1][2]  # a new undo step
    finally:
        engine.shutdown()


def _spin(ms: int) -> None:
    loop = QEventLoop()
    QTimer.singleShot(ms, loop.quit)
    loop.exec_()


def test_a_light_drag_previews_in_the_docker_and_writes_the_layer_once(qapp):
    """While a light moves the docker shows previews and the canvas is left alone (Krita recomposites the whole
    image per layer update); the layer is written when the drag rests and when it ends: one undo step, taken when
    the drag starts."""
    host = FakeHost(w=800, h=640, alpha=cutout_alpha(800, 640, (320, 160, 480, 560)))
    c, engine, messages, _ = make(host)
    shown = []
    c.previewed.connect(lambda rgb, w, h: shown.append((len(rgb), w, h)))
    try:
        moved(c, 0.3, 0.6, True, dragging=True)  # before any Generate: nothing to preview, nothing written
        assert not c.busy and not shown and not host.writes
        c.model.edit_light_map(c.model.light_map, False)
        c.generate()
        assert wait_until(lambda: not c.busy and len(host.writes) == 1)
        assert wait_until(lambda: shown)  # the image with its new shadow, after Generate
        shown.clear()
        for i in range(20):  # a drag, faster than the rest delay
            moved(c, 0.2 + 0.02 * i, 0.6, i == 0, dragging=True)
            _spin(40)
        assert len(host.writes) == 1 and len(shown) >= 3, messages
        assert shown[-1] == (320 * 256 * 3, 320, 256)  # the 800 x 640 image at the preview's size
        c.model.edit_light_map(c.model.light_map, False)  # the release
        assert wait_until(lambda: not c.busy and len(host.writes) == 2)
        # the drag's one undo step was taken at its start (the shadow layer replaced by a copy of itself, with the
        # settings of the shadow it shows); the release writes in place into that copy
        assert host.takeovers == ["shadow-copy-0"] and not host.writes[1][2]
        assert c.model.shadows["shadow-copy-0"].light_map == c.model.light_map

        moved(c, 0.7, 0.5, True, dragging=True)
        assert wait_until(lambda: len(host.writes) == 3, 5)  # the drag rests: the layer follows, in place
        assert len(host.takeovers) == 2 and not host.writes[2][2]
        moved(c, 0.75, 0.5, False, dragging=True)
        c.model.edit_light_map(c.model.light_map, False)  # it moved on, then the release: in place, the same step
        assert wait_until(lambda: not c.busy and len(host.writes) == 4)
        assert not host.writes[3][2] and len(host.takeovers) == 2
        moved(c, 0.8, 0.5, True, dragging=True)
        assert wait_until(lambda: len(host.writes) == 5, 5) and not host.writes[4][2]
        c.model.edit_light_map(c.model.light_map, False)  # released where it rested: nothing new
        _spin(200)
        assert len(host.writes) == 5 and not c.busy and len(host.takeovers) == 3
        host.shadow = None  # no shadow layer (the user deleted it): the release adds one, the drag's undo step
        moved(c, 0.3, 0.5, True, dragging=True)
        c.model.edit_light_map(c.model.light_map, False)
        assert wait_until(lambda: not c.busy and len(host.writes) == 6)
        assert host.writes[5][2] and len(host.takeovers) == 3
        assert not [m for m in messages if m[0] != "info"], messages
    finally:
        engine.shutdown()


def test_live_off_does_not_render(qapp):
    host = FakeHost()
    c, engine, messages, _ = make(host)
    c.live = False
    moved(c, 0.3, 0.5, True)
    c.model.opacity = 0.5
    assert not c.busy and not host.writes
    engine.stop()


def test_source_problems_are_shown_not_raised(qapp):
    host = FakeHost(fail="Select the layer that holds the cutout.")
    c, engine, messages, _ = make(host)
    c.generate()
    assert not c.busy and messages[-1] == ("warning", "Select the layer that holds the cutout.")
    engine.stop()


def test_empty_alpha_message(qapp):
    host = FakeHost(alpha=bytes(200 * 160))
    c, engine, messages, _ = make(host)
    try:
        c.generate()
        assert wait_until(lambda: not c.busy)
        assert messages[-1][0] == "warning" and not host.writes
    finally:
        engine.shutdown()


def test_missing_worker_message_and_recovery(qapp):
    commands = [EngineConfig(("/nonexistent/python", "-m", "ssn_engine", "serve"))]
    host = FakeHost()
    c, engine, messages, _ = make(host, lambda: commands[-1])
    try:
        c.generate()
        assert wait_until(lambda: not c.busy)
        assert messages[-1][0] == "error" and "could not start the shadow engine" in messages[-1][1]
        commands.append(worker_command())  # fixed (e.g. re-installed): the next request restarts it
        c.generate()
        assert wait_until(lambda: not c.busy and host.writes)
    finally:
        engine.shutdown()


def test_worker_crash_mid_session_recovers(qapp):
    host = FakeHost()
    c, engine, messages, _ = make(host)
    try:
        c.generate()
        assert wait_until(lambda: not c.busy and host.writes)
        engine._proc.kill()  # the worker dies
        assert wait_until(lambda: not engine.running)
        moved(c, 0.3, 0.5, True)  # needs the cutout again: sent again from the kept source
        assert wait_until(lambda: not c.busy and len(host.writes) == 2), messages
    finally:
        engine.shutdown()


def test_the_camera_reaches_the_worker_and_changes_the_shadow(qapp):
    """A horizon set in the docker: the worker's cutout is analysed again with it (the camera alone is sent, not
    the alpha again), and the shadow changes. Before it, the worker says which camera the model read from the
    outline; after it, none."""
    host = FakeHost()
    c, engine, messages, _ = make(host)
    reads, sent = [], []
    c.model.camera_read_changed.connect(reads.append)
    request = engine.request

    def spy(cmd, buffers=None, **kwargs):
        alpha = (buffers or {}).get("alpha")
        sent.append((cmd, len(memoryview(alpha.data).cast("B")) if alpha is not None else 0))
        return request(cmd, buffers, **kwargs)

    engine.request = spy
    try:
        c.generate()
        assert wait_until(lambda: not c.busy and host.writes), messages
        first_cutout = c.cutout
        assert wait_until(lambda: reads), messages
        assert reads[-1] is not None and set(reads[-1]) == {"horizon", "fov"}  # blind: the model read one
        assert ("set_cutout", host.w * host.h) in sent
        del sent[:]
        c.model.horizon, c.model.fov = -400.0, 40.0  # seen from high above
        assert len(host.writes) == 1  # not given yet: the same camera, nothing rendered
        c.model.use_horizon = True
        assert wait_until(lambda: not c.busy and len(host.writes) == 2), messages
        assert c.cutout == first_cutout and ("set_camera", 0) in sent  # the same cutout, a new camera
        assert all(cmd != "set_cutout" and nbytes == 0 for cmd, nbytes in sent), sent  # no alpha sent again
        assert reads[-1] is None
        assert host.writes[1][0] != host.writes[0][0]  # the shadow's rectangle moved or changed size
        assert not [m for m in messages if m[0] == "error"]
    finally:
        engine.shutdown()


def test_cancel_stops_waiting_for_a_hung_worker(qapp):
    """A worker that never answers: Cancel frees the docker at once, and nothing is written."""
    host = FakeHost()
    hung = EngineProcess(lambda: worker_command("-c", "import time; time.sleep(60)"), timeout_s=120.0)
    c = ShadowController(hung, host)
    messages = []
    c.model.status_changed.connect(messages.append)
    c.generate()
    assert c.busy
    c.cancel()
    assert not c.busy and not hung.running and not host.writes
    assert messages[-1][0] == "warning" and "Cancelled" in messages[-1][1]
    c.cancel()  # idle: nothing happens
    assert messages[-1][1].startswith("Cancelled")


def test_after_generate_the_preview_shows_the_shadow_and_horizon(qapp):
    """Not only while a light is dragged: after each Generate the docker's preview shows the image with the
    shadow and the horizon the engine used (the only place the horizon is drawn)."""
    host = FakeHost()
    c, engine, messages, _ = make(host)
    previews = []
    c.previewed.connect(lambda rgb, w, h: previews.append((w, h)))
    try:
        c.generate()
        assert wait_until(lambda: not c.busy and previews), messages
        assert previews == [(200, 160)]  # the fake image's size (under the preview's 320 px)
    finally:
        engine.shutdown()


def test_an_undo_brings_back_the_settings_of_the_shadow_it_shows(qapp):
    """Krita's undo brings back an older shadow layer: the docker shows the light map that shadow was made with
    (and keeps the cutout's layer active); an undo that leaves a shadow without a record changes nothing."""
    from plugin_krita.ssn_shadow.shared import light_map as lm

    host = FakeHost()
    c, engine, messages, _ = make(host)
    try:
        c.live = False
        c.model.light_map = lm.preset("low-sun-left")
        c.generate()
        assert wait_until(lambda: not c.busy and len(host.writes) == 1), messages
        first = host.shadow
        c.model.light_map = lm.preset("low-sun-right")
        c.model.opacity = 0.5
        c.generate()
        assert wait_until(lambda: not c.busy and len(host.writes) == 2), messages
        assert host.shadow != first and set(c.model.shadows) == {first, host.shadow}

        host.shadow = first  # Ctrl+Z, twice: the first shadow layer is back on the canvas
        c.history_changed()
        assert c.model.light_map == lm.preset("low-sun-left") and c.model.opacity == 0.85
        assert host.kept_active == 1 and len(host.writes) == 2  # nothing rendered: the canvas shows it already
        host.shadow = "a-layer-the-docker-never-wrote"
        c.history_changed()
        assert c.model.light_map == lm.preset("low-sun-left") and len(host.writes) == 2
        # an undo or a layer added that leaves the same shadow layer (a stroke undone on the shadow the user
        # selected): that layer stays active
        kept = host.kept_active
        c.history_changed()
        assert host.kept_active == kept
    finally:
        engine.shutdown()


def test_a_light_change_after_the_cutout_was_painted_on_renders_the_new_cutout(qapp):
    """The cutout's pixels change after Generate (half of it erased, more alpha painted): the next edit reads it
    again and sends the new cutout to the worker, without a Generate; the renders within one edit (a drag's rest
    and release, a slider's moves) and an edit of an unchanged cutout do not send it again."""
    host = FakeHost()
    c, engine, messages, _ = make(host)
    sent = []
    request = engine.request
    engine.request = lambda cmd, *a, **k: (sent.append(cmd), request(cmd, *a, **k))[1]
    try:
        c.generate()
        assert wait_until(lambda: not c.busy and len(host.writes) == 1), messages
        key = c.source.key
        moved(c, 0.3, 0.6, True)  # an unchanged cutout: read again, not sent again
        assert wait_until(lambda: not c.busy and len(host.writes) == 2), messages
        assert host.refreshes == 1 and sent.count("set_cutout") == 1 and c.source.key == key

        host.alpha = cutout_alpha(200, 160, (80, 40, 100, 140))  # half of the cutout erased
        for i in range(5):  # a slider's drag: read again at its first change only
            moved(c, 0.35 + 0.01 * i, 0.6, i == 0)
        assert wait_until(lambda: not c.busy and sent.count("set_cutout") == 2), messages
        assert host.refreshes == 2 and c.source.alpha == host.alpha and c.source.key != key
        assert not [m for m in messages if m[0] == "error"], messages

        host.alpha = cutout_alpha(200, 160, (60, 40, 120, 140))  # more alpha painted, then a light drag
        writes = len(host.writes)
        for i in range(4):
            moved(c, 0.4 + 0.01 * i, 0.6, i == 0, dragging=True)
        moved(c, 0.45, 0.6, False)  # the release
        assert wait_until(lambda: not c.busy and len(host.writes) > writes), messages
        assert host.refreshes == 3 and sent.count("set_cutout") == 3 and c.source.alpha == host.alpha
        assert host.reads == 1  # always the cutout of the Generate, read again, never the active layer afresh
    finally:
        engine.shutdown()


def test_a_cutout_emptied_since_it_was_read_is_reported_not_rendered(qapp):
    """The cutout's layer was erased entirely: the next edit says so (a warning) and writes nothing."""
    host = FakeHost()
    c, engine, messages, _ = make(host)
    try:
        c.generate()
        assert wait_until(lambda: not c.busy and len(host.writes) == 1), messages
        host.fail = "The layer 'Person' is empty on the canvas: nothing to cast a shadow from."
        moved(c, 0.3, 0.6, True)
        assert wait_until(lambda: not c.busy)
        assert messages[-1] == ("warning", host.fail) and len(host.writes) == 1
    finally:
        engine.shutdown()


class SlowWorker:
    """An engine whose replies wait until the test lets the worker answer (a slow worker); a preview's image is
    grey at the level of the first light's u, so the test can tell which light a shown preview is of."""

    def __init__(self):
        self.waiting: list[tuple[str, dict, dict, object]] = []
        self.sent: list[tuple[str, dict]] = []
        self.most_previews_waiting = 0

    def request(self, cmd, buffers=None, *, on_reply=None, on_error=None, timeout=None, **params):
        self.sent.append((cmd, params))
        self.waiting.append((cmd, params, buffers or {}, on_reply))
        queued = sum(1 for w in self.waiting if w[0] == "preview")
        self.most_previews_waiting = max(self.most_previews_waiting, queued)
        return len(self.sent)

    def answer(self) -> None:
        """The worker answers its oldest request."""
        cmd, params, buffers, on_reply = self.waiting.pop(0)
        if cmd != "preview":
            raise AssertionError(f"only previews expected during a drag, got {cmd}")
        h, w = buffers["background"].shape[:2]
        level = round(255 * params["light_map"]["lights"][0]["u"])
        on_reply({}, {"image": np.full((h, w, 3), level, np.uint8)})


def test_a_drag_while_the_worker_is_slow_keeps_one_preview_pending_and_ends_with_the_last_light(qapp):
    """Moves come faster than the worker answers: never more than one preview request waits at the worker (no
    stale previews queue up behind it), the moves in between become one request with the light of the moment,
    and the drag ends showing the last light's preview."""
    worker = SlowWorker()
    host = FakeHost(w=800, h=640, alpha=cutout_alpha(800, 640, (320, 160, 480, 560)))
    c = ShadowController(worker, host)
    c.source, c.cutout = host.read_source(host.document), "c1"  # as after a Generate
    c._cutout_geometry = (0.0, None)  # its lift and thickness, set at Generate
    shown = []
    c.previewed.connect(lambda rgb, w, h: shown.append(rgb[0]))
    for i in range(60):  # the mouse at 60 Hz, the worker answering one in 7 moves
        moved(c, 0.2 + 0.01 * i, 0.6, i == 0, dragging=True)
        if i % 7 == 6 and worker.waiting:
            worker.answer()
    while worker.waiting:
        worker.answer()
    previews = [params for cmd, params in worker.sent if cmd == "preview"]
    assert worker.most_previews_waiting == 1
    assert 8 <= len(previews) <= 10  # one per answer, and the one the last answer sent: not one per move
    last = round(255 * (0.2 + 0.01 * 59))
    assert previews[-1]["light_map"]["lights"][0]["u"] == pytest.approx(0.79)
    assert shown[-1] == last and len(shown) == len(previews)
    assert [cmd for cmd, _ in worker.sent] == ["preview"] * len(previews)  # the layer waits for the release


def test_the_preview_is_rendered_as_large_as_the_docker_draws_it():
    """The worker renders (and traces a small light on) each pixel of a preview: a preview drawn in a 280 x 175
    box is asked for at that size, not larger; at most PREVIEW_SIDE pixels a side."""
    assert preview_side(2000, 2000, (280, 175)) == 175
    assert preview_side(4000, 3000, (280, 175)) == 234  # 233.3 rounded up: it fills the box's height
    assert preview_side(800, 200, (280, 175)) == 280
    assert preview_side(8000, 1000, (1200, 200)) == PREVIEW_SIDE  # a wide dock: at most that
    assert preview_side(800, 640, None) == PREVIEW_SIDE  # no preview shown yet


def _top_shadow_row(host, threshold=0.05):
    """The canvas row of the last written layer's topmost row with alpha above ``threshold`` of its darkest."""
    (_x, y, w, h), alpha = host.writes[-1][0], host.pixels[3::4]
    darkest = max(alpha)
    rows = [r for r in range(h) if max(alpha[r * w : (r + 1) * w]) > threshold * darkest]
    return y + rows[0]


def test_a_lift_moves_the_shadow_down_through_set_geometry_without_sending_the_alpha_again(qapp):
    """The lift and thickness go to the worker with set_geometry (the cutout is not sent again), each change the
    same layer path as a light change (one undo step; a drag previewed, its release written in place); Generate
    reads the thickness the outline has; a lift whose ground would lie above the horizon is clamped first, with
    the reason."""
    from plugin_krita.ssn_shadow.shared import light_map as lm

    host = FakeHost(w=400, h=400, alpha=cutout_alpha(400, 400, (160, 60, 240, 220)))  # lowest row 219
    c, engine, messages, _ = make(host)
    sent = []
    request = engine.request
    engine.request = lambda cmd, *a, **k: (
        sent.append((cmd, k.get("lift"), k.get("thickness"))),
        request(cmd, *a, **k),
    )[1]
    shown = []
    c.previewed.connect(lambda rgb, w, h: shown.append(w))
    try:
        c.live = False  # the settings, then Generate
        c.model.light_map = lm.preset("high-sun")  # behind the object: its shadow comes towards the viewer
        c.model.horizon, c.model.use_horizon = 100.0, True
        c.live = True
        c.generate()
        assert wait_until(lambda: not c.busy and len(host.writes) == 1), messages
        assert [s[0] for s in sent][:3] == ["set_cutout", "get_ao", "set_geometry"]
        assert isinstance(c.model.thickness_read, float) and c.model.thickness_read > 0  # shown by the slider
        assert c.model.ground == ((160, 60, 240, 220), (400, 400), 219)  # the lift counts from its lowest row
        resting = _top_shadow_row(host)

        sent.clear()
        c.model.edit_lift(60.0)  # the lift box: one new undo step
        assert wait_until(lambda: not c.busy and len(host.writes) == 2), messages
        assert [s[0] for s in sent][:2] == ["set_geometry", "render"] and sent[0][1:] == (60.0, None)
        assert host.writes[1][2] and not [m for m in messages if m[0] != "info"], messages
        lifted = _top_shadow_row(host)
        assert lifted >= resting + 20, (resting, lifted)  # the shadow leaves the object: it starts lower

        sent.clear()
        shown.clear()
        for lift in (70.0, 80.0, 90.0):  # the preview's handle dragged: previews, no layer until the release
            c.model.edit_lift(lift, False, dragging=True)
            _spin(60)
        assert wait_until(lambda: shown) and len(host.writes) == 2
        assert "set_cutout" not in [s[0] for s in sent] and ("set_geometry", 70.0, None) in sent
        c.model.edit_lift(90.0, False)  # the release
        assert wait_until(lambda: not c.busy and len(host.writes) == 3), messages
        assert not host.writes[2][2]  # in place: the drag's undo step was taken at its start
        assert _top_shadow_row(host) > lifted

        sent.clear()
        c.model.edit_thickness(3.0)
        assert wait_until(lambda: not c.busy and len(host.writes) == 4), messages
        assert [s[0] for s in sent][:2] == ["set_geometry", "render"] and sent[0][1:] == (90.0, 3.0)

        # the horizon moved below the object's foot: at the next render the lift is clamped to put its ground
        # below it (the engine refuses a ground at or above the horizon), and says so
        sent.clear()
        c.model.horizon = 330.0
        assert wait_until(lambda: not c.busy and len(host.writes) == 5), messages
        assert c.model.lift == 112.0 and "raised to 112" in c.model.status[1], c.model.status
        assert [s[0] for s in sent if s[0] not in ("get_ao", "preview")] == [
            "set_geometry",
            "set_camera",
            "set_geometry",
            "render",
        ]
        assert [s[1] for s in sent if s[0] == "set_geometry"] == [0.0, 112.0]
        assert not [m for m in messages if m[0] == "error"], messages
    finally:
        engine.shutdown()
