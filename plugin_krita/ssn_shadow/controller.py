"""The docker's conversation with the worker: source -> engine cutout -> AO -> render -> shadow layer.

The controller renders what its :class:`model.ShadowModel` (the active
document's) says, as the model's ``edited`` signal asks, and reports back into
the model (status, the camera the engine read). What each request holds is
built in :mod:`worker_requests`; when requests go out, in :mod:`scheduling`.

Renders are coalesced (latest wins): while one is in flight, further requests
merge into one pending request, which is sent as soon as the reply arrives and
before that reply's layer is written, so the worker computes the next frame
while Krita writes the current one. Only SR re-runs while a light moves; the
cutout's AO (and its edits) stay in the worker.

While a light is dragged the docker shows a live preview instead: the image
without its shadow layer as a thumbnail, with the shadow the worker multiplies
on (coalesced the same way). Krita's scripting API can only recomposite the
whole image, which on a large canvas allows a few layer updates a second; so
the layer is written when the drag rests (``PAUSE_MS``) and when it ends, one
undo step for the whole drag. After a render that is an undo step of its own
(Generate, a preset, the camera...) the preview shows the image with its new
shadow and the horizon, so the horizon the engine used is always in view.

A lift or thickness change (the Geometry section, the preview's lift handle) goes the same way as a light's:
``set_geometry`` tells the worker (the alpha is not sent again), then the preview follows a drag and the layer
its rests and release, or the layer follows a single change at once.

Each layer write records which settings made that shadow layer
(:meth:`model.ShadowModel.record_shadow`); after Krita's undo or redo,
:meth:`ShadowController.history_changed` shows the settings of the shadow
layer the canvas now shows, and gives the cutout's layer back the focus where
the undo made its shadow layer the active one.
"""

from __future__ import annotations

import math
import time
from typing import Any

from PyQt5.QtCore import QObject, QTimer, pyqtSignal

from . import worker_requests
from .adapters.krita_document import Source, SourceError
from .adapters.pixel_format import UnsupportedFormat
from .engine import EngineError
from .model import Settings, ShadowModel
from .properties import Property
from .scheduling import Drag, LatestWins, RenderJob, RenderQueue
from .shared import camera_rules, shadow_notes

PREVIEW_SIDE = 320  # pixels: the longer side of the docker's live preview at most
PAUSE_MS = 300  # a drag that rests this long writes the layer


def preview_side(width: int, height: int, box: tuple[int, int] | None) -> int:
    """The longer side of the preview of a ``width`` x ``height`` image shown in ``box`` (the preview's width
    and height in device pixels; None: not shown yet): as large as it is drawn there, at most ``PREVIEW_SIDE``.
    The worker's time for a preview grows with its pixels (a small light is traced on each)."""
    if box is None:
        return PREVIEW_SIDE
    scale = min(box[0] / max(width, 1), box[1] / max(height, 1))
    return max(1, min(PREVIEW_SIDE, math.ceil(max(width, height) * scale)))


class ShadowController(QObject):
    """Realises a model's shadow through the engine worker, and writes it into the document."""

    busy_changed = pyqtSignal(bool)
    live_changed = pyqtSignal(bool)
    aoChanged = pyqtSignal(bytes, bytes, int)  # AO map, framed mask (N x N uint8 each), N
    rendered = pyqtSignal(dict)  # {"elapsed_ms", "timing_ms", "width", "height", "created", "method"}
    engineReady = pyqtSignal(dict)
    previewed = pyqtSignal(bytes, int, int)  # packed RGB, width, height: the live preview of a light drag

    busy: Property[bool] = Property(False, readonly=True)  # a request is in flight
    live: Property[bool] = Property(True)  # follow each edit with a render (else only Generate renders)

    def __init__(self, engine: Any, host: Any, model: ShadowModel | None = None, parent: QObject | None = None) -> None:
        super().__init__(parent)
        self.engine, self.host = engine, host
        self.model = model if model is not None else ShadowModel()
        self.model.edited.connect(self._edited)
        self.source: Source | None = None
        self.cutout: str | None = None
        self._cutout_key: str | None = None
        self._cutout_camera: dict | None = None  # the camera the worker's cutout has
        self._cutout_geometry: tuple[float, float | None] | None = None  # its lift and thickness (None: unknown)
        self._mask = b""
        self._shadow_seen: str | None = None  # the source's shadow layer as the docker last saw it (its id)
        self._renders = RenderQueue()
        self._edits = LatestWins()
        self._previews = LatestWins()
        self.renders = 0
        self.previews = 0
        self._layer_key: Any = None  # the light map, lift and thickness of the last layer render sent
        self._background: tuple[int, int, bytes] | None = None  # the preview's image without its shadow
        self._preview_due = False  # a render that is an undo step of its own: the preview follows it
        self.preview_box: tuple[int, int] | None = None  # where the preview is drawn, device pixels (the panel's)
        self._drag: Drag | None = None
        self._pause = QTimer(self)
        self._pause.setSingleShot(True)
        self._pause.timeout.connect(self._drag_rested)
        if hasattr(engine, "ready"):
            engine.ready.connect(self.engineReady.emit)

    # -- public API (called by the UI) ------------------------------------------
    def set_model(self, model: ShadowModel) -> None:
        """Render another document's model from now on (the next Generate reads that document afresh)."""
        if model is self.model:
            return
        self.model.edited.disconnect(self._edited)
        self.model = model
        model.edited.connect(self._edited)
        self.forget_cutout()

    def watch_history(self) -> None:
        """Follow Krita's undo and redo (:meth:`history_changed`); call again when Krita may have made its
        actions anew (another window)."""
        if hasattr(self.host, "watch_history"):
            self.host.watch_history(self.history_changed)

    def history_changed(self) -> None:
        """Krita undid or redid a step, or added a layer: the docker shows the settings of the shadow layer now on
        the canvas (where it knows them), and where that step brought a shadow layer (back) into the image, which
        Krita makes the active layer, the cutout's layer is made active again (a shadow layer the user selected
        stays active)."""
        source = self.source
        if source is None or self.host.active_document() != source.document:
            return
        shown = self.host.shadow_layer_id(source)
        if shown != self._shadow_seen:
            self.host.keep_source_active(source)
        self._shadow_seen = shown
        settings = self.model.shadow_shown(shown)
        if settings is None:
            return
        self._layer_key = (settings.light_map.copy(), settings.lift, settings.thickness)
        if self.cutout is not None:  # the AO edits it shows (a camera of its own re-sends the cutout anyway)
            self._send_edits()
        self._refresh_preview()

    def generate(self) -> None:
        """Read the source again and render; the layer write is one new undo step."""
        self._preview_due = True
        self._schedule(RenderJob(new_step=True, reread=True, started=time.perf_counter()))

    def horizon_from_guide(self) -> None:
        """Give the model's horizon on the active document's first horizontal guide (or say how to add one)."""
        if not self.model.horizon_from_guides(self.host.horizontal_guides(self.host.active_document())):
            self.model.report_status("warning", camera_rules.NO_GUIDE)

    def cancel(self) -> None:
        """Stop waiting for the engine (a hung or slow analysis): the worker is stopped and restarts with the
        next request; the image is left as it is."""
        if not self.busy:
            return
        self.engine.cancel()
        self.cutout, self._cutout_key = None, None
        self._edits.clear()
        self._previews.clear()
        self._fail("Cancelled. The shadow engine starts again with the next Generate.", "warning")

    def forget_cutout(self) -> None:
        """Another document or view: the next render reads its source afresh."""
        self.cutout, self._cutout_key, self.source = None, None, None
        self._drag, self._background, self._preview_due = None, None, False
        self._pause.stop()

    # -- the model's edits ----------------------------------------------------------
    def _edited(self, what: str, new_step: bool) -> None:
        if what in ("light_map", "geometry"):  # a drag previews; its release, or a single change, renders
            if self.model.dragging(what):
                self._light_dragged()
            else:
                self._light_map_set(new_step)
        elif what == "ao_edits":
            if self.cutout is not None:
                self._send_edits()
                self._rerender(new_step)
        else:
            self._rerender(new_step)

    def _rerender(self, new_step: bool, preview: bool = True, refresh: bool | None = None) -> None:
        """Re-render at once when Live is on and a shadow exists; ``preview``: a new undo step updates the
        preview when it is written (a drag's updates it already); ``refresh`` (default: ``new_step``, an edit's
        first render): read the cutout again first, which may have been painted on since it was read."""
        if self.live and self.source is not None:
            self._preview_due = self._preview_due or (new_step and preview)
            refresh = new_step if refresh is None else refresh
            self._schedule(RenderJob(new_step=new_step, reread=False, started=time.perf_counter(), refresh=refresh))

    def _layer_key_now(self) -> tuple:
        """What a drag changes in the layer: the light map, the lift and the thickness."""
        return (self.model.light_map, self.model.lift, self.model.thickness)

    def _light_map_set(self, new_step: bool) -> None:
        """The map (or the lift or thickness) changed; it ends a previewed drag. A map equal to the last one
        rendered, as after the last move of a live drag, renders nothing new."""
        drag, self._drag = self._drag, None
        self._pause.stop()
        key = self._layer_key_now()
        if drag is not None:  # the drag's layer: its undo step unless a rest already wrote one
            if key != self._layer_key or not drag.wrote:  # the cutout was read again at the drag's start
                self._rerender(new_step or not drag.wrote, preview=False, refresh=False)
            return
        if key == self._layer_key and not new_step:
            return
        self._rerender(new_step)

    def _light_dragged(self) -> None:
        """A light (or the lift or thickness) is being dragged: update the docker's preview (:attr:`previewed`);
        the layer follows when the drag rests or ends. Before a first Generate, or with Live off, nothing is
        rendered."""
        source = self.source
        if not self.live or source is None:
            return
        if self._drag is None:
            if not self._refresh_source():
                return
            self._drag = self._begin_drag(self.source)
        self._background = self._drag.background
        self._pause.start(PAUSE_MS)
        self._request_preview()

    def _drag_rested(self) -> None:
        if self._drag is not None and self._layer_key_now() != self._layer_key:
            self._rerender(not self._drag.wrote, preview=False, refresh=False)
            self._drag.wrote = True

    def _refresh_source(self) -> bool:
        """Read the cutout again where it changed since it was read (painted on, erased, an undo): a changed one
        is sent to the worker again (its analysis and AO are of the old pixels). False, with a warning, where it
        cannot be read now (emptied, say)."""
        source = self.source
        assert source is not None, "called with a source"
        try:
            self.source = fresh = self.host.refresh_source(source)
        except (SourceError, UnsupportedFormat) as exc:
            self.model.report_status("warning", str(exc))
            return False
        if fresh is not source and fresh.key != self._cutout_key:
            self.cutout, self._cutout_key = None, None  # this drag: the layer alone follows, with the new cutout
        return True

    def _begin_drag(self, source: Source | None) -> Drag:
        """The drag's undo step at its start, where the host makes one (the shadow layer replaced by a copy of
        itself, which the drag's writes then fill in place: Krita recomposites the image once for the layer
        written on release instead of twice), and the preview's background (None: no preview)."""
        assert source is not None, "a drag starts from a source"
        begin = getattr(self.host, "begin_drag", None)
        if self.cutout is None or begin is None:  # the worker restarted: the layer alone follows
            return Drag(self._take_background(source))
        shown = self.host.shadow_layer_id(source)  # its settings are the copy's
        try:
            background, replaced = begin(source, self._preview_side(source))
        except Exception as exc:  # the UI boundary
            self.model.report_status("warning", f"No live preview: {type(exc).__name__}: {exc}")
            return Drag(None)
        if replaced is None:
            return Drag(background)
        self._shadow_seen = replaced.layer_id
        settings = self.model.shadows.get(shown) if shown is not None else None
        if settings is not None:
            self.model.record_shadow(replaced.layer_id, settings)
        return Drag(background, wrote=True)

    # -- preview ------------------------------------------------------------------
    def _preview_side(self, source: Source) -> int:
        return preview_side(source.width, source.height, self.preview_box)

    def _take_background(self, source: Source) -> tuple[int, int, bytes] | None:
        """The image without its shadow for the preview (None: no preview; the layer still follows)."""
        if self.cutout is None:  # the worker restarted: the layer alone follows
            return None
        try:
            return self.host.preview_background(source, self._preview_side(source))
        except Exception as exc:  # the UI boundary
            self.model.report_status("warning", f"No live preview: {type(exc).__name__}: {exc}")
            return None

    def _refresh_preview(self) -> None:
        """Show the image with the shadow now on the canvas (and its horizon) in the preview."""
        if self.source is not None and self._drag is None:
            self._background = self._take_background(self.source)
            self._request_preview()

    def _request_preview(self) -> None:
        background, source, cutout = self._background, self.source, self.cutout
        if background is None or source is None or cutout is None:
            return
        if not self._previews.begin():
            return  # latest wins: sent with the map of the moment when the reply comes

        def send() -> None:
            params, buffers = worker_requests.preview(self.model, cutout, source, background)
            self.engine.request(
                "preview", buffers, on_reply=self._on_preview, on_error=self._on_preview_error, **params
            )

        self._ensure_geometry(send, self._on_preview_error)

    def _on_preview(self, reply: dict, buffers: dict) -> None:
        if self._previews.end():
            self._request_preview()
        image = buffers.get("image")
        if image is not None and len(image.shape) == 3:
            self.previews += 1
            self.previewed.emit(bytes(image.data), int(image.shape[1]), int(image.shape[0]))

    def _on_preview_error(self, error: EngineError) -> None:
        self._previews.clear()
        if error.kind in ("UnknownCutout", "WorkerUnavailable"):
            self.cutout, self._cutout_key = None, None  # the drag's end sends the cutout again
        else:
            self.model.report_status("warning", f"Live preview: {error}")

    # -- scheduling ---------------------------------------------------------------
    def _schedule(self, job: RenderJob) -> None:
        now = self._renders.submit(job)
        if now is not None:
            self._run(now)

    def _set_busy(self, busy: bool) -> None:
        type(self).busy.set(self, busy)

    def _fail(self, message: str, level: str = "error") -> None:
        self._renders.clear()
        self._set_busy(False)
        self.model.report_status(level, message)

    def _run(self, job: RenderJob) -> None:
        self._renders.start()
        self._set_busy(True)
        try:
            if job.reread or self.source is None:
                source = self.host.read_source(self.host.active_document())
                if self.source is not None and source.node_id != self.source.node_id:
                    self.model.clear_ao_edits()
                self.source = source
            elif job.refresh:
                self.source = self.host.refresh_source(self.source)
            self._ensure_cutout(lambda: self._render(job), job)
        except (SourceError, UnsupportedFormat) as exc:
            self._fail(str(exc), "warning")
        except Exception as exc:  # the UI boundary: never let an error reach Krita
            self._fail(f"Soft Shadow could not read the image: {type(exc).__name__}: {exc}")

    def _ensure_cutout(self, render: Any, job: RenderJob) -> None:
        source = self.source
        assert source is not None, "a job reads its source first"
        camera = self.model.camera

        def refused(error: EngineError) -> None:  # a lift or thickness the worker does not take: said, not fatal
            if error.kind == "BadRequest":
                self._fail(str(error), "warning")
            else:
                self._on_error(error, job)

        def then() -> None:
            self._ensure_geometry(render, refused)

        if self.cutout is not None and source.key == self._cutout_key:
            if camera == self._cutout_camera:
                then()
                return
            if self._cutout_geometry is None or self._cutout_geometry[0] > 0:
                # a lift is checked against the camera in use: the worker's cutout rests on the ground while the
                # camera changes, and takes the lift again (clamped to the new horizon) after it
                self._cutout_geometry = (0.0, self.model.thickness)
                params = {**worker_requests.set_geometry(self.model, self.cutout), "lift": 0.0}
                self.engine.request("set_geometry", on_reply=lambda r, b: None, on_error=lambda e: None, **params)
            # A new camera for the same alpha: the worker predicts the AO again (it depends on the camera) and
            # keeps the AO edits; the alpha is not sent again.
            self.model.report_status("info", "Analysing the cutout (ambient occlusion)...")

            def on_camera(reply: dict, buffers: dict) -> None:
                self._cutout_camera = camera
                self._analysed(reply)
                then()

            self.engine.request(
                "set_camera",
                cutout=self.cutout,
                camera=camera,
                on_reply=on_camera,
                on_error=lambda e: self._on_error(e, job),
            )
            return
        self.model.report_status("info", "Analysing the cutout (ambient occlusion)...")

        def on_cutout(reply: dict, buffers: dict) -> None:
            self.cutout, self._cutout_key, self._cutout_camera = reply["cutout"], source.key, camera
            self._cutout_geometry = None  # set_geometry follows (it reads the thickness the outline has)
            edits = self.model.ao_edit_list()
            if edits:
                self.engine.request(
                    "edit_ao",
                    cutout=self.cutout,
                    edits=edits,
                    on_reply=self._on_ao_edited,
                    on_error=self._on_edit_error,
                )
            self._analysed(reply)
            then()

        params, buffers = worker_requests.set_cutout(source, camera)
        self.engine.request(
            "set_cutout", buffers, on_reply=on_cutout, on_error=lambda e: self._on_error(e, job), **params
        )

    def _analysed(self, reply: dict) -> None:
        """A cutout analysed (with its camera): report the camera the model read and the cutout's ground, and
        fetch the AO map."""
        self.model.report_camera_read(reply.get("camera_read"))
        source = self.source
        if source is not None and reply.get("bbox"):
            self.model.report_ground(reply["bbox"], (source.width, source.height), reply.get("lift_row"))
        self.engine.request("get_ao", cutout=self.cutout, on_reply=self._on_ao)

    def _ensure_geometry(self, then: Any, on_error: Any) -> None:
        """The worker's cutout takes the model's lift and thickness (``set_geometry``: the alpha is not sent again;
        its reply says the thickness read), clamped first to the cutout's ground and camera now known; then
        ``then()``, or ``on_error(error)`` where the worker refused it (the render or preview that asked is
        dropped)."""
        self.model.clamp_geometry()
        wanted = (float(self.model.lift), self.model.thickness)
        if self.cutout is None or wanted == self._cutout_geometry:
            then()
            return
        self._cutout_geometry = wanted

        def on_geometry(reply: dict, buffers: dict) -> None:
            self.model.report_geometry(reply)
            then()

        def on_refused(error: EngineError) -> None:
            self._cutout_geometry = None  # the worker kept its geometry: send it again with the next edit
            on_error(error)

        params = worker_requests.set_geometry(self.model, self.cutout)
        self.engine.request("set_geometry", on_reply=on_geometry, on_error=on_refused, **params)

    def _render(self, job: RenderJob) -> None:
        source, cutout = self.source, self.cutout
        assert source is not None and cutout is not None, "a job reads its source and sends its cutout first"
        self._layer_key = (self.model.light_map.copy(), self.model.lift, self.model.thickness)
        model, settings = self.model, self.model.settings()  # the settings this shadow is rendered from
        params, blend = worker_requests.render(model, cutout, source)  # the blend of the colour rendered
        self.engine.request(
            "render",
            on_reply=lambda reply, buffers: self._on_rendered(job, source, blend, reply, buffers, (model, settings)),
            on_error=lambda e: self._on_error(e, job),
            **params,
        )

    # -- replies --------------------------------------------------------------------
    def _on_rendered(
        self, job: RenderJob, source: Source, blend: str, reply: dict, buffers: dict, made: tuple[ShadowModel, Settings]
    ) -> None:
        nxt = self._renders.finish()
        if nxt is not None:
            self._run(nxt)  # the worker renders the next frame while this one is written
        if not self.host.is_open(source.document):  # closed meanwhile: nothing to write, nothing to say
            if not self._renders.in_flight:
                self._set_busy(False)
            return
        rect = (int(reply["x"]), int(reply["y"]), int(reply["width"]), int(reply["height"]))
        layer = buffers.get("layer")
        try:
            pixels = bytes(layer.data) if layer is not None else b""
            result = self.host.write(source, pixels, rect, job.new_step, blend)
        except Exception as exc:  # the UI boundary
            self._fail(f"Soft Shadow could not write the shadow layer: {type(exc).__name__}: {exc}")
            return
        if result.layer_id:
            made[0].record_shadow(result.layer_id, made[1])
            self._shadow_seen = result.layer_id
        self.renders += 1
        elapsed = 1e3 * (time.perf_counter() - job.started) if job.started else 0.0
        info = {
            "elapsed_ms": round(elapsed, 1),
            "timing_ms": reply.get("timing_ms", {}),
            "width": rect[2],
            "height": rect[3],
            "created": result.created,
            "method": reply.get("method", ""),
        }
        if result.notice:
            self.model.report_status("warning", result.notice)
        elif rect[2] == 0:
            self.model.report_status("warning", shadow_notes.no_shadow_note(reply.get("no_shadow")))
        elif self.model.clamped:  # a lift or thickness clamped for this render: why, not the timing
            self.model.report_status("warning", self.model.clamped)
        elif job.new_step:
            self.model.report_status("info", f"Shadow {rect[2]} x {rect[3]} px in {elapsed:.0f} ms ({info['method']}).")
        self.model.clamped = ""
        if not self._renders.in_flight:
            self._set_busy(False)
            if self._preview_due and self._drag is None:
                self._preview_due = False
                self._refresh_preview()
        self.rendered.emit(info)

    def _on_error(self, error: EngineError, job: RenderJob) -> None:
        if error.kind in ("UnknownCutout", "WorkerUnavailable"):
            self.cutout, self._cutout_key = None, None  # the next request sends the cutout again
        if error.kind == "UnknownCutout" and not job.retried:
            # The worker restarted (it died while idle, or dropped the cutout): send the cutout again, once.
            self._renders.in_flight = False
            self._run(RenderJob(job.new_step, True, job.started, retried=True))
            return
        level = "warning" if error.kind == "EmptyAlpha" else "error"
        self._fail(str(error), level)

    def _on_ao(self, reply: dict, buffers: dict) -> None:
        ao, mask = buffers.get("ao"), buffers.get("mask")
        if ao is not None and mask is not None:
            self._mask = bytes(mask.data)
            self.aoChanged.emit(bytes(ao.data), self._mask, int(ao.shape[0]))

    def _send_edits(self) -> None:
        if not self._edits.begin():
            return
        self.engine.request(
            "edit_ao",
            cutout=self.cutout,
            edits=self.model.ao_edit_list(),
            on_reply=self._on_ao_edited,
            on_error=self._on_edit_error,
        )

    def _on_ao_edited(self, reply: dict, buffers: dict) -> None:
        again = self._edits.end()
        ao = buffers.get("ao")
        if ao is not None and self._mask:
            self.aoChanged.emit(bytes(ao.data), self._mask, int(ao.shape[0]))
        if again and self.cutout is not None:
            self._send_edits()

    def _on_edit_error(self, error: EngineError) -> None:
        self._edits.clear()
        self.model.report_status("error", str(error))
