"""The docker's logic: source -> engine cutout -> AO -> render -> shadow layer, asynchronously.

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
undo step for the whole drag.
"""

from __future__ import annotations

import time
from dataclasses import dataclass
from typing import Any

from PyQt5.QtCore import QObject, QTimer, pyqtSignal

from .adapters.krita_document import SourceError
from .adapters.pixel_format import UnsupportedFormat, blend_mode, shadow_color
from .engine import EngineError
from .shared import camera_rules, defaults, protocol, shadow_notes
from .shared import light_map as lm


PREVIEW_SIDE = 320  # pixels: the longer side of the docker's live preview
PAUSE_MS = 300  # a drag that rests this long writes the layer


def document_key(document: Any) -> str:
    """What identifies a document for remembered settings: its file, or (unsaved) the object."""
    return document.fileName() or f"unsaved:{id(document)}"


@dataclass
class RenderJob:
    """One wanted render; ``new_step`` makes its layer write an undo step, ``reread`` re-reads the source;
    ``retried``: it already sent the cutout again once (after a worker restart)."""

    new_step: bool
    reread: bool
    started: float = 0.0
    retried: bool = False

    def merge(self, other: RenderJob) -> RenderJob:
        return RenderJob(self.new_step or other.new_step, self.reread or other.reread, self.started or other.started)


@dataclass
class Drag:
    """A light drag in progress: the preview's background ((width, height, RGBA), None when there is no
    preview) and whether the drag has written its layer yet (at a rest)."""

    background: tuple[int, int, bytes] | None
    wrote: bool = False


class ShadowController(QObject):
    """State of one docker and the requests that realise it."""

    busyChanged = pyqtSignal(bool)
    status = pyqtSignal(str, str)  # level ("info" | "warning" | "error"), text for people
    aoChanged = pyqtSignal(bytes, bytes, int)  # AO map, framed mask (N x N uint8 each), N
    rendered = pyqtSignal(dict)  # {"elapsed_ms", "timing_ms", "width", "height", "created", "method"}
    engineReady = pyqtSignal(dict)
    previewed = pyqtSignal(bytes, int, int)  # packed RGB, width, height: the live preview of a light drag
    cameraRead = pyqtSignal(object)  # {"horizon", "fov"} the model read from the outline (no camera set), or None

    def __init__(self, engine: Any, host: Any, parent: QObject | None = None) -> None:
        super().__init__(parent)
        self.engine, self.host = engine, host
        self.light_map = lm.preset(lm.DEFAULT_PRESET)
        self.ao_edits: list[dict] = []
        self.color: tuple[float, float, float] = (0.0, 0.0, 0.0)
        self.opacity = defaults.OPACITY
        self.camera: dict | None = None  # {"horizon": canvas row, "fov": degrees}, or None: the default camera
        self._cameras: dict[str, dict | None] = {}  # remembered per document
        self.live = True
        self.source = None
        self.cutout: str | None = None
        self._cutout_key: str | None = None
        self._cutout_camera: dict | None = None  # the camera the worker's cutout has
        self._mask = b""
        self._in_flight = False
        self._pending: RenderJob | None = None
        self._edit_in_flight = False
        self._edit_dirty = False
        self._busy = False
        self.renders = 0
        self.previews = 0
        self._layer_map: Any = None  # the light map of the last layer render sent
        self._drag: Drag | None = None
        self._preview_in_flight = False
        self._preview_pending = False
        self._pause = QTimer(self)
        self._pause.setSingleShot(True)
        self._pause.timeout.connect(self._drag_rested)
        if hasattr(engine, "ready"):
            engine.ready.connect(self._on_engine_ready)

    # -- public API (called by the UI) ------------------------------------------
    @property
    def busy(self) -> bool:
        return self._busy

    def generate(self) -> None:
        """Read the source again and render; the layer write is one new undo step."""
        self._schedule(RenderJob(new_step=True, reread=True, started=time.perf_counter()))

    def lights_edited(self, stroke_started: bool = False) -> None:
        """The light map or the shadow options changed; re-render at once when Live is on and a shadow exists."""
        if self.live and self.source is not None:
            self._schedule(RenderJob(new_step=stroke_started, reread=False, started=time.perf_counter()))

    def set_light_map(self, light_map: Any, stroke_started: bool = True) -> None:
        """The editor's map changed (the controller keeps its own copy); it ends a previewed drag. A map equal
        to the last one rendered, as after the last move of a live drag, renders nothing new."""
        drag, self._drag = self._drag, None
        self._pause.stop()
        self.light_map = light_map.copy()
        if drag is not None:  # the drag's layer: its undo step unless a rest already wrote one
            if light_map != self._layer_map or not drag.wrote:
                self.lights_edited(stroke_started=stroke_started or not drag.wrote)
            return
        if light_map == self._layer_map and not stroke_started:
            return
        self.lights_edited(stroke_started=stroke_started)

    def drag_light_map(self, light_map: Any) -> None:
        """A light is being dragged: update the docker's preview (:attr:`previewed`); the layer follows when the
        drag rests or ends (:meth:`set_light_map`). Before a first Generate, or with Live off, only the map is
        kept."""
        self.light_map = light_map.copy()
        if not self.live or self.source is None:
            return
        if self._drag is None:
            background = None
            if self.cutout is not None:  # else (the worker restarted) the layer alone follows
                try:
                    background = self.host.preview_background(self.source, PREVIEW_SIDE)
                except Exception as exc:  # the UI boundary: no preview, the layer still follows
                    self.status.emit("warning", f"No live preview: {type(exc).__name__}: {exc}")
            self._drag = Drag(background)
        self._pause.start(PAUSE_MS)
        self._request_preview()

    def set_ao_edits(self, edits: list[dict], stroke_started: bool = False) -> None:
        """Replace the AO edits (the whole list); the worker re-applies them to its AO map."""
        self.ao_edits = list(edits)
        if self.cutout is None:
            return
        self._send_edits()
        self.lights_edited(stroke_started=stroke_started)

    def set_camera(self, camera: dict | None) -> None:
        """The image's horizon row and field of view (None: the engine's default camera), remembered for the
        active document; the worker analyses the cutout again with it."""
        self.camera = dict(camera) if camera is not None else None
        document = self.host.active_document()
        if document is not None:
            self._cameras[document_key(document)] = self.camera
        self.lights_edited(stroke_started=True)

    def camera_for(self, document) -> dict | None:
        """The camera remembered for ``document`` (None when none was set)."""
        return self._cameras.get(document_key(document)) if document is not None else None

    def cancel(self) -> None:
        """Stop waiting for the engine (a hung or slow analysis): the worker is stopped and restarts with the
        next request; the image is left as it is."""
        if not self._busy:
            return
        self.engine.cancel()
        self.cutout, self._cutout_key = None, None
        self._edit_in_flight = self._edit_dirty = False
        self._preview_in_flight = self._preview_pending = False
        self._fail("Cancelled. The shadow engine starts again with the next Generate.", "warning")

    def _drag_rested(self) -> None:
        if self._drag is not None and self.light_map != self._layer_map:
            self.lights_edited(stroke_started=not self._drag.wrote)
            self._drag.wrote = True

    def _request_preview(self) -> None:
        drag, source = self._drag, self.source
        if drag is None or drag.background is None or source is None or self.cutout is None:
            return
        if self._preview_in_flight:
            self._preview_pending = True  # latest wins: sent with the map of the moment when the reply comes
            return
        self._preview_in_flight, self._preview_pending = True, False
        width, height, rgba = drag.background
        params: dict[str, Any] = {
            "cutout": self.cutout,
            "light_map": self.light_map.to_dict(),
            "color": list(self.color),  # the thumbnail is 8-bit sRGB, whatever the document's profile
            "opacity": self.opacity,
        }
        if self.camera:
            params["horizon"] = camera_rules.scaled_camera(self.camera, width / source.width)["horizon"]
        else:
            params["read_horizon"] = True  # the horizon the model read, dotted
        background = protocol.Buffer("uint8", (height, width, 4), rgba)
        self.engine.request(
            "preview", {"background": background}, on_reply=self._on_preview, on_error=self._on_preview_error, **params
        )

    def _on_preview(self, reply: dict, buffers: dict) -> None:
        self._preview_in_flight = False
        if self._preview_pending:
            self._request_preview()
        image = buffers.get("image")
        if image is not None and len(image.shape) == 3:
            self.previews += 1
            self.previewed.emit(bytes(image.data), int(image.shape[1]), int(image.shape[0]))

    def _on_preview_error(self, error: EngineError) -> None:
        self._preview_in_flight = self._preview_pending = False
        if error.kind in ("UnknownCutout", "WorkerUnavailable"):
            self.cutout, self._cutout_key = None, None  # the drag's end sends the cutout again
        else:
            self.status.emit("warning", f"Live preview: {error}")

    def forget_cutout(self) -> None:
        self.cutout, self._cutout_key, self.source = None, None, None

    # -- scheduling ---------------------------------------------------------------
    def _schedule(self, job: RenderJob) -> None:
        if self._in_flight:
            self._pending = job if self._pending is None else self._pending.merge(job)
            return
        self._run(job)

    def _set_busy(self, busy: bool) -> None:
        if busy != self._busy:
            self._busy = busy
            self.busyChanged.emit(busy)

    def _fail(self, message: str, level: str = "error") -> None:
        self._in_flight, self._pending = False, None
        self._set_busy(False)
        self.status.emit(level, message)

    def _run(self, job: RenderJob) -> None:
        self._in_flight = True
        self._set_busy(True)
        try:
            if job.reread or self.source is None:
                source = self.host.read_source(self.host.active_document())
                if self.source is not None and source.node_id != self.source.node_id:
                    self.ao_edits = []
                self.source = source
            self._ensure_cutout(lambda: self._render(job), job)
        except (SourceError, UnsupportedFormat) as exc:
            self._fail(str(exc), "warning")
        except Exception as exc:  # the UI boundary: never let an error reach Krita
            self._fail(f"Soft Shadow could not read the image: {type(exc).__name__}: {exc}")

    def _ensure_cutout(self, then: Any, job: RenderJob) -> None:
        source = self.source
        assert source is not None, "a job reads its source first"
        camera = dict(self.camera) if self.camera else None
        if self.cutout is not None and source.key == self._cutout_key:
            if camera == self._cutout_camera:
                then()
                return
            # A new camera for the same alpha: the worker predicts the AO again (it depends on the camera) and
            # keeps the AO edits; the alpha is not sent again.
            self.status.emit("info", "Analysing the cutout (ambient occlusion)...")

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
        self.status.emit("info", "Analysing the cutout (ambient occlusion)...")
        alpha = protocol.Buffer(source.dtype, (source.height, source.width), source.alpha)

        def on_cutout(reply: dict, buffers: dict) -> None:
            self.cutout, self._cutout_key, self._cutout_camera = reply["cutout"], source.key, camera
            if self.ao_edits:
                self.engine.request(
                    "edit_ao",
                    cutout=self.cutout,
                    edits=self.ao_edits,
                    on_reply=self._on_ao_edited,
                    on_error=self._on_edit_error,
                )
            self._analysed(reply)
            then()

        params = {"camera": camera} if camera else {}
        self.engine.request(
            "set_cutout", {"alpha": alpha}, on_reply=on_cutout, on_error=lambda e: self._on_error(e, job), **params
        )

    def _analysed(self, reply: dict) -> None:
        """A cutout analysed (with its camera): show the camera the model read, and fetch the AO map."""
        self.cameraRead.emit(reply.get("camera_read"))
        self.engine.request("get_ao", cutout=self.cutout, on_reply=self._on_ao)

    def _render(self, job: RenderJob) -> None:
        source = self.source
        assert source is not None, "a job reads its source first"
        self._layer_map = self.light_map.copy()
        params = {
            "cutout": self.cutout,
            "light_map": self.light_map.to_dict(),
            "color": shadow_color(self.color, source.profile),
            "opacity": self.opacity,
            "format": source.layer_format.render_format(),
        }
        blend = blend_mode(self.color)  # the mode of the colour rendered, whatever the colour is by the reply
        self.engine.request(
            "render",
            on_reply=lambda reply, buffers: self._on_rendered(job, source, blend, reply, buffers),
            on_error=lambda e: self._on_error(e, job),
            **params,
        )

    # -- replies --------------------------------------------------------------------
    def _on_rendered(self, job: RenderJob, source: Any, blend: str, reply: dict, buffers: dict) -> None:
        nxt, self._pending = self._pending, None
        self._in_flight = False
        if nxt is not None:
            self._run(nxt)  # the worker renders the next frame while this one is written
        rect = (int(reply["x"]), int(reply["y"]), int(reply["width"]), int(reply["height"]))
        layer = buffers.get("layer")
        try:
            pixels = bytes(layer.data) if layer is not None else b""
            result = self.host.write(source, pixels, rect, job.new_step, blend)
        except Exception as exc:  # the UI boundary
            self._fail(f"Soft Shadow could not write the shadow layer: {type(exc).__name__}: {exc}")
            return
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
            self.status.emit("warning", result.notice)
        elif rect[2] == 0:
            self.status.emit("warning", shadow_notes.no_shadow_note(reply.get("no_shadow")))
        elif job.new_step:
            self.status.emit("info", f"Shadow {rect[2]} x {rect[3]} px in {elapsed:.0f} ms ({info['method']}).")
        if not self._in_flight:
            self._set_busy(False)
        self.rendered.emit(info)

    def _on_error(self, error: EngineError, job: RenderJob) -> None:
        if error.kind in ("UnknownCutout", "WorkerUnavailable"):
            self.cutout, self._cutout_key = None, None  # the next request sends the cutout again
        if error.kind == "UnknownCutout" and not job.retried:
            # The worker restarted (it died while idle, or dropped the cutout): send the cutout again, once.
            self._in_flight = False
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
        if self._edit_in_flight:
            self._edit_dirty = True
            return
        self._edit_in_flight, self._edit_dirty = True, False
        self.engine.request(
            "edit_ao",
            cutout=self.cutout,
            edits=self.ao_edits,
            on_reply=self._on_ao_edited,
            on_error=self._on_edit_error,
        )

    def _on_ao_edited(self, reply: dict, buffers: dict) -> None:
        self._edit_in_flight = False
        ao = buffers.get("ao")
        if ao is not None and self._mask:
            self.aoChanged.emit(bytes(ao.data), self._mask, int(ao.shape[0]))
        if self._edit_dirty and self.cutout is not None:
            self._send_edits()

    def _on_edit_error(self, error: EngineError) -> None:
        self._edit_in_flight = self._edit_dirty = False
        self.status.emit("error", str(error))

    def _on_engine_ready(self, info: dict) -> None:
        self.engineReady.emit(info)
