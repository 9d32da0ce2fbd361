"""Runs inside Krita (kritarunner): the docker's previews per second while a light is dragged, the layer after
the release, and Generate latency.

Started by ``python -m plugin_krita.benchmark``; writes JSON to $SSN_BENCH_RESULT.
"""

import json
import os
import struct
import time
import traceback
from typing import Any

from krita import Krita
from PyQt5.QtCore import QEventLoop, QTimer
from PyQt5.QtWidgets import QApplication

RESULT = os.environ.get("SSN_BENCH_RESULT", "/tmp/ssn_bench.json")
DRAG_S = float(os.environ.get("SSN_BENCH_DRAG_S", "8"))
RELEASES = 5  # releases timed per depth (their median is reported)
DEPTHS = os.environ.get("SSN_BENCH_DEPTHS", "U8,U16,F16,F32").split(",")
# The presets whose light is dragged for the preview table: a Gaussian the network renders, a 0.53-degree sun traced
LIGHTS = [name for name in os.environ.get("SSN_BENCH_LIGHTS", "softbox,sun").split(",") if name]
out: dict[str, Any] = {"live": {}, "previews": {}}
PIXEL_BYTES = {"U8": 4, "U16": 8, "F16": 8, "F32": 16}
# the parts of a release reported (medians, ms): the release to the written layer, and where its time went
RELEASE_PARTS = (
    "to_layer",
    "request_after",
    "waiting",
    "worker",
    "worker_shadow",
    "worker_layer",
    "reply_transfer",
    "after_reply",
    "write",
    "longest_stall",
)


def pixel(depth, bgr, a):
    """One pixel of the cutout in Krita's layout for ``depth`` (integer: B, G, R, A; float: R, G, B, A)."""
    if depth == "U8":
        return bytes([*bgr, a])
    if depth == "U16":
        return struct.pack("<4H", *(257 * v for v in (*bgr, a)))
    rgba = [v / 255 for v in (*bgr[::-1], a)]
    return struct.pack("<4e" if depth == "F16" else "<4f", *rgba)


def save():
    with open(RESULT, "w") as f:
        json.dump(out, f, indent=1)


def document(w, h, depth="U8"):
    doc = Krita.instance().createDocument(w, h, f"bench-{w}x{h}-{depth}", "RGBA", depth, "", 72.0)
    root = doc.rootNode()
    person = doc.createNode("Person", "paintlayer")
    x0, x1, y0, y1 = int(0.4 * w), int(0.6 * w), int(0.2 * h), int(0.75 * h)
    row = pixel(depth, (40, 90, 200), 255) * (x1 - x0)
    person.setPixelData(row * (y1 - y0), x0, y0, x1 - x0, y1 - y0)
    root.addChildNode(person, root.childNodes()[0])
    window = Krita.instance().openWindow()  # a real view: the canvas redraws as the layer changes
    window.addView(doc)
    doc.setActiveNode(person)
    doc.waitForDone()
    deadline = time.monotonic() + 10
    while getattr(doc.activeNode(), "name", lambda: None)() != "Person" and time.monotonic() < deadline:
        QApplication.processEvents()
        time.sleep(0.01)
    return doc


def _median(values):
    return round(sorted(values)[len(values) // 2], 1) if values else None


def controller_for(doc):
    from ssn_shadow.adapters.host import KritaHost
    from ssn_shadow.controller import ShadowController
    from ssn_shadow.engine import EngineProcess

    host = KritaHost(Krita.instance())
    host.active_document = lambda: doc
    return ShadowController(EngineProcess(), host)


def trace_replies(engine):
    """Per request of each command: when it was sent, when its reply's first and last bytes arrived, and in how
    many reads (the reply's bytes come through the worker's pipe as Krita's event loop reads them)."""
    traced: dict[str, list] = {}
    sent: dict[Any, tuple[str, float]] = {}
    state: dict[str, Any] = {"first": None, "chunks": 0}
    request, feed = engine.request, engine._decoder.feed

    def traced_request(cmd, *args, **kwargs):
        t = time.perf_counter()
        rid = request(cmd, *args, **kwargs)
        sent[rid] = (cmd, t)
        return rid

    def traced_feed(data):
        t = time.perf_counter()
        state["first"] = state["first"] or t
        state["chunks"] += 1
        messages = feed(data)
        for header, _ in messages:
            entry = sent.pop(header.get("id"), None)
            if entry is not None:
                cmd, at = entry
                first: float = state["first"] or t
                traced.setdefault(cmd, []).append((at, max(first, at), time.perf_counter(), state["chunks"]))
            state["first"], state["chunks"] = None, 0
        return messages

    engine.request, engine._decoder.feed = traced_request, traced_feed
    return traced


def timed(obj, name):
    """Wrap ``obj.name`` so that each call's milliseconds are appended to the returned list."""
    call, times = getattr(obj, name), []

    def timed_call(*args):
        t = time.perf_counter()
        result = call(*args)
        times.append(1e3 * (time.perf_counter() - t))
        return result

    setattr(obj, name, timed_call)
    return times


def spin(controller, timeout_s):
    loop = QEventLoop()
    QTimer.singleShot(int(timeout_s * 1000), loop.quit)
    connection = controller.busy_changed.connect(lambda busy: None if busy else loop.quit())
    if controller.busy:
        loop.exec_()
    controller.busy_changed.disconnect(connection)


def spin_for(seconds):
    loop = QEventLoop()
    QTimer.singleShot(int(seconds * 1000), loop.quit)
    loop.exec_()


def preview_drag(doc, light):
    """The preset ``light``'s light dragged on the docker's light map at the mouse's rate for DRAG_S, through the
    docker's own panel (its map and preview drawn, its settings saved in the document as in Krita): the previews
    per second, the gaps between them and where the time goes (the worker's render of each preview, its round
    trip from the request to the reply's last byte)."""
    from ssn_shadow.persistence import DocumentModels
    from ssn_shadow.shared import light_map
    from ssn_shadow.ui.panel import ShadowPanel

    c = controller_for(doc)
    c.set_model(DocumentModels(c.host).model_for(doc))
    panel = ShadowPanel(c)
    panel.resize(300, 700)  # the docker's preferred width
    panel.show()
    c.model.light_map = light_map.preset(light)
    c.generate()
    spin(c, 120)
    previews, worker_ms, sizes = [], [], set()

    def previewed(rgb, w, h):
        previews.append(time.perf_counter())
        sizes.add((w, h))

    c.previewed.connect(previewed)
    request = c.engine.request

    def timed_request(cmd, *args, on_reply=None, **kwargs):
        answer = on_reply
        if cmd == "preview" and answer is not None:

            def timed_reply(reply, buffers):
                worker_ms.append(sum(reply.get("timing_ms", {}).values()))
                answer(reply, buffers)

            on_reply = timed_reply
        return request(cmd, *args, on_reply=on_reply, **kwargs)

    c.engine.request = timed_request
    replies = trace_replies(c.engine)
    editor, moves = panel.map_widget.editor, {"i": 0}
    start = c.model.light_map.lights[0]
    editor.press(start.u, start.v)

    def move():  # what the map widget does on each mouse move of a drag
        moves["i"] += 1
        editor.drag(0.30 + 0.4 * ((moves["i"] % 240) / 240.0), 0.6)

    timer = QTimer()
    timer.timeout.connect(move)
    timer.start(16)  # 60 Hz
    loop = QEventLoop()
    QTimer.singleShot(int(DRAG_S * 1000), loop.quit)
    t0 = time.perf_counter()
    loop.exec_()
    timer.stop()
    editor.release()
    spin(c, 30)
    in_window = [t for t in previews if t <= t0 + DRAG_S]
    gaps = [b - a for a, b in zip(in_window, in_window[1:], strict=False)]
    trips = [done - sent for sent, _, done, _ in replies.get("preview", [])]
    out["previews"][light] = {
        "canvas": f"{doc.width()}x{doc.height()}",
        "mouse_moves": moves["i"],
        "previews_per_s": round(len(in_window) / DRAG_S, 2),
        "median_preview_gap_ms": _median([1e3 * g for g in gaps]),
        "median_worker_ms": _median(worker_ms),
        "median_round_trip_ms": _median([1e3 * t for t in trips]),
        "preview_sizes": sorted(sizes),
    }
    panel.close()
    c.engine.shutdown()


def live_drag(doc, depth):
    """A light dragged at the mouse's rate: the docker's previews per second, no layer writes until the
    release; then RELEASES short drags, each released: the time from the release to the written layer, and its
    parts (the worker's render, the host's write), and what each drag's start costs Krita."""
    c = controller_for(doc)
    messages = out.setdefault("live_messages", {})[depth] = []
    c.model.status_changed.connect(lambda status: messages.append(list(status)) if status[0] != "info" else None)
    c.generate()
    spin(c, 120)
    previews, writes = [], []
    c.previewed.connect(lambda rgb, w, h: previews.append(time.perf_counter()))
    c.rendered.connect(lambda info: writes.append((time.perf_counter(), info)))
    write_ms, start_ms = timed(c.host, "write"), timed(c.host, "begin_drag")
    reread_ms = timed(c.host, "refresh_source")  # a drag's start reads the cutout again (where it changed)
    replies = trace_replies(c.engine)
    light = {"i": 0}
    editor = c.model.light_map.copy()

    def move():  # what the light map widget does on every mouse move (60 Hz)
        light["i"] += 1
        editor.move(0, 0.30 + 0.4 * ((light["i"] % 240) / 240.0), 0.6)
        c.model.edit_light_map(editor, light["i"] == 1, dragging=True)

    def drag(seconds):
        timer = QTimer()
        timer.timeout.connect(move)
        timer.start(16)
        loop = QEventLoop()
        QTimer.singleShot(int(seconds * 1000), loop.quit)
        loop.exec_()
        timer.stop()

    t0 = time.perf_counter()
    drag(DRAG_S)
    in_window = [t for t in previews if t <= t0 + DRAG_S]
    gaps = sorted(b - a for a, b in zip(in_window, in_window[1:], strict=False))
    during = len(writes)
    releases = []
    ticks: list[float] = []  # the event loop's turns during a release (a 1 ms timer): its longest stall
    ticker = QTimer()
    ticker.timeout.connect(lambda: ticks.append(time.perf_counter()))
    for _ in range(RELEASES):
        # A short drag: a preview is in flight at the release, as after a real one. Its first move, the drag's
        # start, is made before the quarter second (at 16 bit and float it holds the event loop 0.3 s, which
        # would otherwise end the drag as its first preview leaves, the release waiting for all of it).
        move()
        drag(0.25)
        ticks.clear()
        ticker.start(1)
        released, start = time.perf_counter(), len(writes)
        c.model.edit_light_map(editor, False)
        spin(c, 30)
        spin_for(0.03)  # a turn of the event loop after the write
        ticker.stop()
        if len(writes) > start:
            at, info = writes[start]
            sent, first, done, chunks = replies["render"][-1]
            turns = [released] + [t for t in ticks if t <= at] + [t for t in ticks if t > at][:1]
            stall = max((b - a for a, b in zip(turns, turns[1:], strict=False)), default=0.0)
            worker = info["timing_ms"]
            releases.append(
                {
                    "to_layer": 1e3 * (at - released),
                    "write": write_ms[start],
                    "worker": sum(worker.values()),
                    **{f"worker_{part}": ms for part, ms in worker.items()},
                    "created": info["created"],
                    "request_after": 1e3 * (sent - released),
                    # from the request to the reply's first byte, less the render: the preview still in flight
                    # at the release, the worker reading the request and writing the reply
                    "waiting": 1e3 * (first - sent) - sum(worker.values()),
                    "reply_transfer": 1e3 * (done - first),
                    "reply_chunks": chunks,
                    "after_reply": 1e3 * (at - done) - write_ms[start],  # decoding, dispatch, the signal
                    "layer_mb": info["width"] * info["height"] * PIXEL_BYTES[depth] / 1e6,
                    "longest_stall": 1e3 * stall,
                }
            )
    out["live"][depth] = {
        "canvas": "2000x2000",
        "drag_s": DRAG_S,
        "mouse_moves": light["i"],
        "previews": len(in_window),
        "previews_per_s": round(len(in_window) / DRAG_S, 2),
        "median_preview_gap_ms": round(1e3 * gaps[len(gaps) // 2], 1) if gaps else None,
        "layer_writes_during_drag": during,
        "releases": len(releases),
        **{f"release_{k}_ms": _median([r[k] for r in releases]) for k in RELEASE_PARTS},
        "release_new_layer": any(r["created"] for r in releases),
        "drag_start_ms": _median(start_ms[1:]),  # the releases' drags (their undo step, the preview's background)
        "drag_reread_ms": _median(reread_ms[1:]),  # the same drags' cutout read again (or not: nothing changed)
        "release_reply_chunks": _median([r["reply_chunks"] for r in releases]),
        "release_layer_mb": _median([r["layer_mb"] for r in releases]),
        "total_s": round(time.perf_counter() - t0, 2),
    }
    c.engine.shutdown()


def generate_latency(doc, runs=3):
    c = controller_for(doc)
    c.generate()  # warm: worker start, model load
    spin(c, 120)
    times = []
    for i in range(runs):
        c.forget_cutout()  # a fresh cutout each time: the full path (read alpha, AO, render, write)
        lights = c.model.light_map.copy()
        lights.move(0, 0.3 + 0.1 * i, 0.6)
        c.model.light_map = lights  # no source after forget_cutout: nothing renders before the Generate
        t = time.perf_counter()
        c.generate()
        spin(c, 120)
        times.append(round(1e3 * (time.perf_counter() - t), 1))
    out["generate_4000x3000_ms"] = times
    c.engine.shutdown()


def main(*args):
    try:
        for light in LIGHTS:
            preview_drag(document(2000, 2000), light)
            save()
        for depth in DEPTHS:
            live_drag(document(2000, 2000, depth), depth)
            save()
        generate_latency(document(4000, 3000))
        out["done"] = True
    except Exception:
        out["error"] = traceback.format_exc()
    save()
