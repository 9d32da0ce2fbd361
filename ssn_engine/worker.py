"""The engine worker behind ``ssn-shadow serve`` (protocol: docs/protocol.md).

It keeps one method (model) loaded and one session per cutout (one :class:`ShadowSession` per object on the
layer: :func:`ssn_engine.layer_session.open_session`), and answers requests over stdin/stdout or a loopback TCP
socket. Every
request header is checked before its buffers are read (known command, sizes
that add up, at most ``MAX_REQUEST_BYTES`` of buffers, a bounded canvas); a
refused request gets a ``BadRequest`` reply and the worker goes on serving.
Over a loopback socket (:mod:`ssn_engine.loopback`) a connection reaches it
only after ``auth`` with the worker's per-start token.
"""

from __future__ import annotations

import collections
import ctypes
import dataclasses
import itertools
import os
import sys
import time
import traceback
from typing import IO, Any

import numpy as np

from . import __version__
from .ao_edit import AOEditError
from .host_kit.camera_rules import DEFAULT_FOV, check_fov
from .compositing import preview_image, shadow_layer
from .framing import EmptyAlphaError, Framing
from .host_kit.light_map import PRESETS, LightMap, LightMapError, preset
from .layer_session import LayerSession, open_session
from .methods import LoadedMethod, ModelError
from .host_kit.protocol import (
    PROTOCOL_VERSION,
    Buffer,
    BufferSpec,
    ProtocolError,
    read_buffers,
    read_header,
    skip,
    write_message,
)
from .session import ShadowSession, no_shadow_reason

Session = ShadowSession | LayerSession

MAX_SESSIONS = 8
MAX_PREVIEW_SIDE = 4096  # pixels, either side of a preview's background
MAX_REQUEST_BYTES = 1 << 30  # buffers of one request
MAX_CANVAS_SIDE = 32768  # pixels, either side of a set_cutout alpha
MAX_CANVAS_PIXELS = 1 << 28  # 268 megapixels
MAX_MARGIN = MAX_CANVAS_SIDE  # pixels a clipped layer may reach past each side of the canvas
REQUEST_BUFFERS = {  # the buffers each command takes; the others take none
    "set_cutout": ("alpha",),
    "preview": ("background",),
}


class RequestError(Exception):
    """A request the worker refuses; ``kind`` is the protocol's error type."""

    def __init__(self, kind: str, message: str) -> None:
        super().__init__(message)
        self.kind = kind


def to_array(buffer: Buffer) -> np.ndarray:
    """A protocol buffer as a read-only numpy array."""
    return np.frombuffer(buffer.data, np.dtype(buffer.dtype).newbyteorder("<")).reshape(buffer.shape)


def to_buffer(array: np.ndarray) -> Buffer:
    """The array as a protocol buffer: a view of its bytes (little-endian), not a copy."""
    array = np.ascontiguousarray(array.astype(array.dtype.newbyteorder("<"), copy=False))
    return Buffer(array.dtype.name, array.shape, array.data.cast("B"))


def _u8(image: np.ndarray) -> Buffer:
    return to_buffer(np.rint(np.clip(image, 0, 1) * 255).astype(np.uint8))


def _check_alpha(alpha: np.ndarray) -> None:
    """A float alpha holds coverage in [0, 1] (NaN reads as transparent, above 1 as opaque); negative or
    infinite values are a host's bug, refused rather than guessed at."""
    if alpha.dtype.kind != "f":
        return
    bad = alpha[np.isinf(alpha) | (alpha < 0)]
    if bad.size:
        raise RequestError(
            "BadRequest",
            f"alpha: a float alpha holds coverage from 0 to 1, got {bad[0]:g} ({bad.size} negative or infinite values)",
        )


def _camera(camera: Any) -> tuple[float, float]:
    """set_cutout's optional ``camera``: {"horizon": canvas row, "fov": degrees (default :data:`DEFAULT_FOV`)}."""
    if not isinstance(camera, dict) or not isinstance(camera.get("horizon"), (int, float)):
        raise RequestError("BadRequest", 'camera: expected {"horizon": ROW, "fov": DEGREES}')
    try:
        fov = check_fov(camera.get("fov", DEFAULT_FOV), "camera.fov")
    except ValueError as exc:
        raise RequestError("BadRequest", str(exc)) from None
    if not np.isfinite(camera["horizon"]):
        raise RequestError("BadRequest", "camera.horizon: expected a finite canvas row")
    return float(camera["horizon"]), float(fov)


def _cutout_reply(key: str, session: Session) -> dict:
    """``set_cutout``'s and ``set_camera``'s reply: the cutout's id, its bounding box, the row its lift counts
    from and, without a camera of the image's own, the camera the model read from its outline."""
    reply: dict[str, Any] = {"cutout": key, "bbox": list(session.framing.bbox), "lift_row": int(session.lift_row)}
    if session.camera_read is not None:
        reply["camera_read"] = session.camera_read
    return reply


class Worker:
    """Request handling, independent of the transport."""

    def __init__(self, loaded: LoadedMethod) -> None:
        self.loaded = loaded
        self.sessions: collections.OrderedDict[str, Session] = collections.OrderedDict()
        self._ids = itertools.count(1)

    # -- helpers -------------------------------------------------------------
    @staticmethod
    def _cutout_key(header: dict) -> str | None:
        """The request's cutout id: a string, or None where it names none (an unknown cutout)."""
        key = header.get("cutout")
        if key is not None and not isinstance(key, str):
            raise RequestError("BadRequest", f"cutout: expected an id that set_cutout answered (a string), got {key!r}")
        return key

    def _session(self, header: dict) -> Session:
        key = self._cutout_key(header)
        if key is None or key not in self.sessions:
            raise RequestError("UnknownCutout", f"unknown cutout {key!r}: send set_cutout first")
        self.sessions.move_to_end(key)
        return self.sessions[key]

    @staticmethod
    def _light_map(header: dict) -> LightMap:
        given = [key for key in ("light_map", "preset") if header.get(key) is not None]
        if len(given) != 1:
            raise RequestError("BadRequest", "light_map or preset: give exactly one")
        if given[0] == "light_map":
            return LightMap.from_dict(header["light_map"])
        return preset(header["preset"])

    # -- commands ------------------------------------------------------------
    def hello(self, header: dict, buffers: dict) -> tuple[dict, dict]:
        m = self.loaded.method
        return {
            "protocol": PROTOCOL_VERSION,
            "version": __version__,
            "method": m.name,
            "method_note": self.loaded.note,
            "resolution": m.resolution,
            "presets": list(PRESETS),
            "pid": os.getpid(),
        }, {}

    def set_cutout(self, header: dict, buffers: dict) -> tuple[dict, dict]:
        if "alpha" not in buffers:
            raise RequestError("BadRequest", "alpha: buffer missing")
        alpha = to_array(buffers["alpha"])  # 2D and bounded: check_request
        _check_alpha(alpha)
        horizon, fov = _camera(header["camera"]) if header.get("camera") is not None else (None, None)
        session = open_session(alpha, self.loaded.method, horizon, fov, layer_opacity=header.get("layer_opacity", 1.0))
        if "lift" in header or "thickness" in header:
            session.set_geometry(header.get("lift", 0.0), header.get("thickness"))
        key = f"c{next(self._ids)}"
        self.sessions[key] = session
        while len(self.sessions) > MAX_SESSIONS:
            self.sessions.popitem(last=False)
        return _cutout_reply(key, session), {}

    def set_camera(self, header: dict, buffers: dict) -> tuple[dict, dict]:
        s = self._session(header)
        if "camera" not in header:
            raise RequestError("BadRequest", 'camera: expected {"horizon": ROW, "fov": DEGREES} or null')
        horizon, fov = _camera(header["camera"]) if header["camera"] is not None else (None, None)
        s.set_camera(horizon, fov)
        return _cutout_reply(header["cutout"], s), {}

    def set_geometry(self, header: dict, buffers: dict) -> tuple[dict, dict]:
        s = self._session(header)
        s.set_geometry(header.get("lift", 0.0), header.get("thickness"))
        reply = {"lift": s.lift, "thickness": s.thickness, "thickness_read": round(s.thickness_read, 4)}
        return {**_cutout_reply(header["cutout"], s), **reply}, {}

    def get_ao(self, header: dict, buffers: dict) -> tuple[dict, dict]:
        s = self._session(header)
        return {}, {"ao": _u8(s.ao), "mask": _u8(s.mask)}

    def edit_ao(self, header: dict, buffers: dict) -> tuple[dict, dict]:
        s = self._session(header)
        edits = header.get("edits")
        if not isinstance(edits, list):
            raise RequestError("BadRequest", "edits: expected a list")
        return {}, {"ao": _u8(s.set_ao_edits(edits))}

    def render(self, header: dict, buffers: dict) -> tuple[dict, dict]:
        light_map = self._light_map(header)
        s = self._session(header)
        fmt = header.get("format") or {}
        if not isinstance(fmt, dict):
            raise RequestError("BadRequest", "format: expected an object")
        clip = header.get("clip", True)
        if not isinstance(clip, bool):
            raise RequestError("BadRequest", "clip: expected true (the layer stays on the canvas) or false")
        margin = header.get("margin", 0)
        if isinstance(margin, bool) or not isinstance(margin, int) or not 0 <= margin <= MAX_MARGIN:
            raise RequestError("BadRequest", f"margin: expected whole pixels in [0, {MAX_MARGIN}], got {margin!r}")
        t0 = time.perf_counter()
        if clip and margin:  # clipped to the canvas grown by the margin, then placed back on the canvas
            shadow = s.render(light_map, s.framing.padded(margin))
            shadow.x, shadow.y = shadow.x - margin, shadow.y - margin
        else:
            shadow = s.render(light_map, clip=clip)
        t1 = time.perf_counter()
        reply = {"x": shadow.x, "y": shadow.y, "width": 0, "height": 0, "method": s.method.name}
        out: dict[str, Buffer] = {}
        reason = no_shadow_reason(light_map, shadow)
        if reason:
            reply["no_shadow"] = reason
        else:
            layer = shadow_layer(
                shadow,
                header.get("color", (0.0, 0.0, 0.0)),
                float(header.get("opacity", 1.0)),
                fmt.get("dtype", "uint8"),
                fmt.get("channels", "rgba"),
            )
            reply.update(width=layer.shape[1], height=layer.shape[0])
            out["layer"] = to_buffer(layer)
        t2 = time.perf_counter()
        reply["timing_ms"] = {
            "shadow": round(1e3 * (t1 - t0), 2),
            "layer": round(1e3 * (t2 - t1), 2),
        }
        return reply, out

    def preview(self, header: dict, buffers: dict) -> tuple[dict, dict]:
        light_map = self._light_map(header)
        s = self._session(header)
        if "background" not in buffers:
            raise RequestError("BadRequest", "background: buffer missing")
        background = to_array(buffers["background"])  # uint8 (h, w, 3|4), bounded: check_request
        framing = self._preview_framing(s, background.shape[1], background.shape[0])
        cover = s.cover(framing)
        horizon = header.get("horizon")
        if horizon is not None and (not isinstance(horizon, (int, float)) or not np.isfinite(horizon)):
            raise RequestError("BadRequest", f"horizon: expected a row number, got {horizon!r}")
        read_horizon = header.get("read_horizon", False)
        if not isinstance(read_horizon, bool):
            raise RequestError("BadRequest", f"read_horizon: expected true or false, got {read_horizon!r}")
        read = s.camera_read_in(framing) if horizon is None and read_horizon else None
        if read is not None:
            horizon = read["horizon"]
        t0 = time.perf_counter()
        shadow = s.render(light_map, framing)
        t1 = time.perf_counter()
        color, opacity = header.get("color", (0.0, 0.0, 0.0)), float(header.get("opacity", 1.0))
        image = preview_image(background, shadow, cover, color, opacity, horizon, read is not None)
        reply: dict[str, Any] = {
            "timing_ms": {"shadow": round(1e3 * (t1 - t0), 2), "image": round(1e3 * (time.perf_counter() - t1), 2)}
        }
        reason = no_shadow_reason(light_map, shadow)
        if reason:
            reply["no_shadow"] = reason
        return reply, {"image": to_buffer(image)}

    @staticmethod
    def _preview_framing(s: Session, width: int, height: int) -> Framing:
        """The cutout's framing for a preview background of ``width`` x ``height``: the cutout's canvas or the
        canvas scaled down (its aspect kept within a pixel, as a host's thumbnail rounds it)."""
        cw, ch = s.framing.canvas_width, s.framing.canvas_height
        factor = width / cw
        scaled = s.framing.scaled(factor) if 0 < factor <= 1.0 else None
        if scaled is None or height < 1 or abs(scaled.canvas_height - height) > 1:
            raise RequestError(
                "BadRequest",
                f"background: {width} x {height}, but the cutout is {cw} x {ch}: send the canvas, or the canvas "
                "scaled down with its aspect ratio",
            )
        if factor == 1.0 and height == ch:
            return s.framing
        return dataclasses.replace(scaled, canvas_height=height)

    def release(self, header: dict, buffers: dict) -> tuple[dict, dict]:
        key = self._cutout_key(header)
        if key is not None and key in self.sessions:
            del self.sessions[key]
        return {}, {}

    COMMANDS = (
        "hello",
        "set_cutout",
        "set_camera",
        "set_geometry",
        "get_ao",
        "edit_ao",
        "render",
        "preview",
        "release",
    )

    def handle(self, header: dict, buffers: dict[str, Buffer]) -> tuple[dict, dict[str, Buffer]]:
        """Answer one request; never raises."""
        base = {"id": header.get("id")}
        cmd = header.get("cmd")
        try:
            if cmd not in self.COMMANDS:
                raise RequestError("BadRequest", f"cmd: unknown command {cmd!r}")
            reply, out = getattr(self, cmd)(header, buffers)
            return {**base, "ok": True, **reply}, out
        except RequestError as exc:
            kind, message = exc.kind, str(exc)
        except EmptyAlphaError as exc:
            kind, message = "EmptyAlpha", str(exc)
        except LightMapError as exc:
            kind, message = "LightMapError", f"light map: {exc}"
        except ModelError as exc:
            kind, message = "ModelError", str(exc)
        except (AOEditError, ValueError, TypeError, ProtocolError) as exc:
            kind, message = "BadRequest", str(exc)
        except MemoryError:
            kind, message = "Internal", "the engine ran out of memory for this request"
        except Exception as exc:  # a bug: report it, keep serving
            traceback.print_exc(file=sys.stderr)
            kind, message = "Internal", f"internal engine error ({type(exc).__name__}: {exc}); please report it"
        return {**base, "ok": False, "error": {"type": kind, "message": message}}, {}

    def check_request(self, header: dict, specs: list[BufferSpec]) -> None:
        """Refuse a request from its header alone (RequestError), before any of its buffers is read."""
        cmd = header.get("cmd")
        if cmd not in self.COMMANDS and cmd not in ("shutdown", "auth"):
            raise RequestError("BadRequest", f"cmd: unknown command {cmd!r}")
        total = sum(s.nbytes for s in specs)
        if total > MAX_REQUEST_BYTES:
            raise RequestError(
                "BadRequest",
                f"request: {total} bytes of buffers, above the worker's limit of "
                f"{MAX_REQUEST_BYTES / 2**30:g} GiB ({MAX_REQUEST_BYTES} bytes)",
            )
        allowed = REQUEST_BUFFERS.get(cmd, ())
        extra = [s.name for s in specs if s.name not in allowed]
        if extra:
            raise RequestError(
                "BadRequest",
                f"{cmd}: unexpected buffer {extra[0]!r}"
                + (f"; it takes {', '.join(allowed)}" if allowed else "; it takes none"),
            )
        for spec in specs:
            if spec.name == "background":
                if len(spec.shape) != 3 or spec.shape[2] not in (3, 4) or spec.dtype != "uint8":
                    raise RequestError(
                        "BadRequest", f"background: expected uint8 (height, width, 3 or 4), got {list(spec.shape)}"
                    )
                if max(spec.shape[:2]) > MAX_PREVIEW_SIDE:
                    raise RequestError("BadRequest", f"background: at most {MAX_PREVIEW_SIDE} pixels a side")
            if spec.name == "alpha":
                if len(spec.shape) != 2:
                    raise RequestError("BadRequest", f"alpha: expected a 2D buffer, got shape {list(spec.shape)}")
                h, w = spec.shape
                if max(h, w) > MAX_CANVAS_SIDE or h * w > MAX_CANVAS_PIXELS:
                    raise RequestError(
                        "BadRequest",
                        f"alpha: a {w} x {h} canvas is above the worker's limit of "
                        f"{MAX_CANVAS_SIDE} pixels a side and {MAX_CANVAS_PIXELS / 1e6:.0f} megapixels",
                    )

    def serve(self, reader: IO[bytes], writer: IO[bytes]) -> bool:
        """Answer requests until the stream ends (False) or a shutdown (True). An ``auth`` is answered ``ok``:
        the loopback socket checked its token before the conversation reached the worker."""
        lost = False
        while True:
            try:
                header, specs = read_header(reader)
            except EOFError:
                return False
            except ProtocolError as exc:
                # Reply once, step over the buffers the header declared when that is safe, else drop lines
                # until one is a header again (a refused header's bytes may still arrive).
                if not lost:
                    _refuse(writer, None, "BadRequest", str(exc))
                lost = not _step_over(reader, exc.skip)
                continue
            lost = False
            rid = header.get("id")
            try:
                self.check_request(header, specs)
            except RequestError as exc:
                _refuse(writer, rid, exc.kind, str(exc))
                lost = not _step_over(reader, sum(s.nbytes for s in specs))
                continue
            try:
                buffers = read_buffers(reader, specs)
            except EOFError:
                return False
            if header.get("cmd") in ("shutdown", "auth"):
                write_message(writer, {"id": rid, "ok": True})
                if header["cmd"] == "shutdown":
                    return True
                continue
            reply, out = self.handle(header, buffers)
            write_message(writer, reply, out)


def _refuse(writer: IO[bytes], rid: Any, kind: str, message: str) -> None:
    write_message(writer, {"id": rid, "ok": False, "error": {"type": kind, "message": message}})


def _step_over(reader: IO[bytes], nbytes: int | None) -> bool:
    """Drop a refused request's buffers; False where their size is unknown or unbounded (not read)."""
    if nbytes is None or nbytes > MAX_REQUEST_BYTES:
        return False
    try:
        skip(reader, nbytes)
    except EOFError:
        return False
    return True


MMAP_THRESHOLD = 64 << 20  # bytes: arrays up to a 4000 x 3000 float32 canvas (48 MB) reuse the heap
TRIM_THRESHOLD = 64 << 20  # bytes of free heap kept for the next request before any is given back


def tune_malloc() -> None:
    """Fixed glibc thresholds for a long-running worker. By default glibc raises its mmap threshold to the
    size of each large block freed (up to 32 MB): arrays then come from the heap or from the OS depending on
    history, and the heap fragments. Fixed thresholds keep one rule: canvas-sized arrays come from the heap,
    whose freed memory is kept for the next request instead of being mapped and zero-filled again (a light
    change on a 4000 x 3000 canvas spent half its time in page faults when every array over 1 MB came fresh
    from the OS). One heap (arena) serves every thread: the network's pass runs on a thread of its own while the
    tracer's warps run on the stripes' threads, and with an arena each, each kept freed canvas-sized blocks of
    its own (over the 500 requests of ``ssn-shadow soak`` the worker's memory grew by 49 to 77 MiB, peak 405 to
    418 MiB, against 0 to 64 MiB, peak 342 to 374, with one: at most the free heap kept, ``TRIM_THRESHOLD``).
    Elsewhere a no-op."""
    try:
        libc = ctypes.CDLL("libc.so.6")
        libc.mallopt(-3, MMAP_THRESHOLD)  # M_MMAP_THRESHOLD
        libc.mallopt(-1, TRIM_THRESHOLD)  # M_TRIM_THRESHOLD
        libc.mallopt(-8, 1)  # M_ARENA_MAX
    except (OSError, AttributeError):
        pass


PIPE_SIZE = 1 << 20  # bytes: Linux's default /proc/sys/fs/pipe-max-size


def widen_pipe(fd: int) -> None:
    """Let the pipe on ``fd`` hold PIPE_SIZE bytes instead of 64 KiB, so that a layer's megabytes reach the
    reader in a few reads rather than hundreds (Krita's event loop reads a reply in 8 to 26 reads instead of 165
    to 364, 2 to 3 times faster). Linux only; elsewhere, or where ``fd`` is no pipe, a no-op."""
    try:
        import fcntl

        fcntl.fcntl(fd, fcntl.F_SETPIPE_SZ, PIPE_SIZE)
    except (ImportError, AttributeError, OSError):
        pass


def serve_stdio(loaded: LoadedMethod) -> None:
    """Serve over stdin/stdout; anything printed goes to stderr instead."""
    tune_malloc()
    reader, writer = sys.stdin.buffer, sys.stdout.buffer
    widen_pipe(writer.fileno())
    sys.stdout = sys.stderr
    print(f"ssn-shadow worker ready: {loaded.note}", file=sys.stderr, flush=True)
    Worker(loaded).serve(reader, writer)
