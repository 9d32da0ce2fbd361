"""Runs inside real Krita (kritarunner): drives the plug-in's generate path against the real worker.

Called as ``kritarunner -s krita_driver -f main`` with the installed plug-in's pykrita folder on
PYTHONPATH; $SSN_TEST_RESULT names the JSON file it writes (kritarunner's exit status says nothing).
"""

import json
import os
import struct
import time
import traceback
from array import array

from krita import Krita, Selection
from PyQt5.QtCore import QEventLoop, QTimer
from PyQt5.QtGui import QImage
from PyQt5.QtWidgets import QApplication

RESULT = os.environ.get("SSN_TEST_RESULT", "/tmp/ssn_krita_result.json")
W, H = 480, 360
OBJ = (200, 90, 280, 270)  # x0, y0, x1, y1 of the opaque cutout
out = {"cases": {}, "log": []}


def save():
    with open(RESULT, "w") as f:
        json.dump(out, f, indent=1)


def pixel(depth, bgr_or_rgb, a):
    if depth == "U8":
        return bytes([*bgr_or_rgb, a])
    if depth == "U16":
        return struct.pack("<4H", *[257 * c for c in bgr_or_rgb], 257 * a)
    if depth in ("F16", "F32"):
        return struct.pack("<4e" if depth == "F16" else "<4f", *[c / 255 for c in bgr_or_rgb], a / 255)
    raise ValueError(depth)


def make_document(depth, with_window):
    k = Krita.instance()
    doc = k.createDocument(W, H, f"ssn-{depth}", "RGBA", depth, "", 72.0)
    if with_window:
        window = k.openWindow()
        window.addView(doc)
    root = doc.rootNode()
    bg = root.childNodes()[0]
    person = doc.createNode("Person", "paintlayer")
    x0, y0, x1, y1 = OBJ
    px = pixel(depth, (40, 90, 200), 255)
    person.setPixelData(px * ((x1 - x0) * (y1 - y0)), x0, y0, x1 - x0, y1 - y0)
    root.addChildNode(person, bg)
    activate(doc, person)
    return doc, person


def activate(doc, node):
    doc.setActiveNode(node)
    doc.waitForDone()
    deadline = time.monotonic() + 10  # with a view, the active node changes via the event loop
    while (doc.activeNode() is None or doc.activeNode().name() != node.name()) and time.monotonic() < deadline:
        QApplication.processEvents()
        time.sleep(0.01)


def pump(seconds):
    """Run the event loop for a while (with a view, Krita switches the active layer through queued events)."""
    deadline = time.monotonic() + seconds
    while time.monotonic() < deadline:
        QApplication.processEvents()
        time.sleep(0.01)


def wait_for(controller, timeout_s=90.0):
    loop = QEventLoop()
    timer = QTimer()
    timer.setSingleShot(True)
    timer.timeout.connect(loop.quit)
    connection = controller.busy_changed.connect(lambda busy: None if busy else loop.quit())
    timer.start(int(timeout_s * 1000))
    if controller.busy:
        loop.exec_()
    controller.busy_changed.disconnect(connection)


def choose(controller, lights=None, color=None):
    """Set the lights (a preset's name) or the colour with Live off, as a user who then presses Generate."""
    from ssn_shadow.shared import light_map as lm

    live, controller.live = controller.live, False
    if lights is not None:
        controller.model.light_map = lm.preset(lights)
    if color is not None:
        controller.model.color = color
    controller.live = live


def alpha_plane(node, depth):
    from ssn_shadow.adapters.pixel_format import extract_alpha, pixel_format

    raw = extract_alpha(bytes(node.pixelData(0, 0, W, H)), pixel_format("RGBA", depth))
    if depth == "U8":
        return [a / 255 for a in raw]
    if depth == "U16":
        return [a / 65535 for a in array("H", raw)]
    if depth == "F16":
        return [v for (v,) in struct.iter_unpack("<e", raw)]
    return list(array("f", raw))


def region_stats(alpha, x0, y0, x1, y1):
    vals = [alpha[y * W + x] for y in range(max(0, y0), min(H, y1)) for x in range(max(0, x0), min(W, x1))]
    return {"sum": round(sum(vals), 3), "max": round(max(vals) if vals else 0.0, 4)}


def layer_names(doc):
    return [n.name() for n in doc.rootNode().childNodes()]


def pixels_of(state):
    """A shadow state without the layer's unique id: what the canvas shows."""
    return {k: v for k, v in state.items() if k != "uid"}


def shadow_state(doc, depth):
    kids = doc.rootNode().childNodes()
    names = [n.name() for n in kids]
    if "Shadow: Person" not in names:
        return {"names": names}
    shadow = kids[names.index("Shadow: Person")]
    alpha = alpha_plane(shadow, depth)
    x0, y0, x1, y1 = OBJ
    h = y1 - y0
    return {
        "names": names,
        "shadow_index": names.index("Shadow: Person"),
        "source_index": names.index("Person"),
        "blend": shadow.blendingMode(),
        "type": shadow.type(),
        "uid": shadow.uniqueId().toString(),
        "far_above": region_stats(alpha, 0, 0, W, y0 - h // 4),
        "below": region_stats(alpha, 0, y1 + 2, W, H),
        "right": region_stats(alpha, x1 + 2, y0 + h // 2, W, y1 + 40),
        "left": region_stats(alpha, 0, y0 + h // 2, x0 - 2, y1 + 40),
        "total": region_stats(alpha, 0, 0, W, H),
    }


def run_case(depth, with_window):
    from ssn_shadow.adapters.host import KritaHost
    from ssn_shadow.controller import ShadowController
    from ssn_shadow.engine import EngineProcess

    k = Krita.instance()
    case = out["cases"][depth] = {}
    doc, person = make_document(depth, with_window)
    source_before = bytes(person.pixelData(0, 0, W, H))
    bg = doc.rootNode().childNodes()[0]
    bg_before = bytes(bg.pixelData(0, 0, W, H))
    case["selection_before"] = doc.selection() is not None
    engine = EngineProcess()
    host = KritaHost(k)
    host.active_document = lambda: doc  # several test documents are open; the docker uses the active one
    controller = ShadowController(engine, host)
    messages = case["messages"] = []
    controller.model.status_changed.connect(lambda status: messages.append(list(status)))
    renders = case["renders"] = []
    controller.rendered.connect(lambda info: renders.append(info))

    choose(controller, "low-sun-left")  # light left of centre: shadow to the right
    t = time.perf_counter()
    controller.generate()
    wait_for(controller)
    case["first_ms"] = round(1e3 * (time.perf_counter() - t), 1)
    case["after_first"] = shadow_state(doc, depth)
    pump(1.0)  # the view changes the active node through the event loop
    case["active_after_first"] = doc.activeNode().name() if doc.activeNode() is not None else None
    save()

    # The worker dies while idle (crash, OOM kill): the next Generate still works, at the first click.
    engine._proc.kill()
    engine._proc.waitForFinished(5000)
    QApplication.processEvents()
    messages_before = len(messages)
    choose(controller, "low-sun-right")  # shadow to the left
    controller.generate()
    wait_for(controller)
    case["after_second"] = shadow_state(doc, depth)
    case["messages_after_worker_death"] = messages[messages_before:]
    case["source_identical"] = bytes(person.pixelData(0, 0, W, H)) == source_before
    case["background_identical"] = bytes(bg.pixelData(0, 0, W, H)) == bg_before
    case["selection_after"] = doc.selection() is not None
    save()

    undo = k.action("edit_undo")
    case["undo_available"] = undo is not None
    if undo is not None:
        steps = case["undo_steps"] = []
        for _ in range(3):  # the second shadow, the first one back, and no shadow: one undo step each
            text = undo.text()
            undo.trigger()
            doc.waitForDone()
            steps.append([text, layer_names(doc)])
        case["source_identical_after_undo"] = bytes(person.pixelData(0, 0, W, H)) == source_before
    save()

    if depth == "U8":  # a selection is the source when there is one, and it stays as it was
        sel = Selection()
        sel.select(OBJ[0], OBJ[1], (OBJ[2] - OBJ[0]) // 2, OBJ[3] - OBJ[1], 255)
        doc.setSelection(sel)
        activate(doc, person)
        sel_before = bytes(doc.selection().pixelData(0, 0, W, H))
        choose(controller, "low-sun-left")
        controller.generate()
        wait_for(controller)
        case["with_selection"] = shadow_state(doc, depth)
        now = doc.selection()
        case["selection_unchanged"] = now is not None and bytes(now.pixelData(0, 0, W, H)) == sel_before
        case["source_identical_after_selection"] = bytes(person.pixelData(0, 0, W, H)) == source_before

        # Select All: no full-canvas shadow; a warning, and the layers as they were
        everything = Selection()
        everything.select(0, 0, W, H, 255)
        doc.setSelection(everything)
        before = shadow_state(doc, depth)
        start = len(messages)
        controller.generate()
        wait_for(controller)
        case["select_all_messages"] = messages[start:]
        case["select_all_unchanged"] = shadow_state(doc, depth) == before

        # The cutout is the lowest layer (issue #14, item 2): a second Generate works too
        low_doc, low = make_document(depth, with_window)
        low_doc.rootNode().childNodes()[0].remove()  # the background: "Person" is now the lowest layer
        low_doc.waitForDone()
        activate(low_doc, low)
        host.active_document = lambda: low_doc
        start, rendered = len(messages), len(renders)
        for _ in range(2):
            controller.generate()
            wait_for(controller)
            pump(1.0)
            activate(low_doc, low)  # whichever layer the view left active, the cutout's is
        case["lowest_layer_messages"] = messages[start:]
        case["lowest_layer_names"] = layer_names(low_doc)
        # ... and from the shadow layer above it, which names its cutout below
        activate(low_doc, low_doc.rootNode().childNodes()[-1])
        controller.generate()
        wait_for(controller)
        case["lowest_layer_renders"] = len(renders) - rendered
        case["lowest_layer_names_from_shadow"] = layer_names(low_doc)
        case["lowest_layer_all_messages"] = messages[start:]

        # The horizon from a guide, through the docker's panel: the shadow is cast again with that camera
        from ssn_shadow.ui.panel import ShadowPanel

        host.active_document = lambda: doc
        doc.setSelection(Selection())  # an empty selection: the layer's alpha again
        # Generate with the shadow layer below the cutout active: it names its cutout, and is replaced
        shadow_layer = next(n for n in doc.rootNode().childNodes() if n.name() == "Shadow: Person")
        activate(doc, shadow_layer)
        start = len(messages)
        controller.generate()
        wait_for(controller)
        case["from_shadow_messages"] = messages[start:]
        case["from_shadow_names"] = layer_names(doc)
        activate(doc, person)
        panel = ShadowPanel(controller)
        controller.generate()
        wait_for(controller)
        case["before_camera"] = shadow_state(doc, depth)
        case["camera_read"] = controller.model.camera_read
        doc.setHorizontalGuides([40.0])
        panel.from_guide.click()
        wait_for(controller)
        case["camera_from_guide"] = controller.model.camera
        case["with_camera"] = shadow_state(doc, depth)

        # The docker in a short dock area (issue #14, item 5): the panel scrolls, at its full height
        from ssn_shadow.docker import SoftShadowDocker

        docker = SoftShadowDocker()
        docker.resize(400, 650)
        docker.show()
        for _ in range(20):
            QApplication.processEvents()
        scroll = docker.panel.scroll
        case["docker"] = {
            "scrolls": docker.widget() is docker.panel and scroll.widget() is docker.panel.body,
            "panel_height": docker.panel.body.height(),
            "panel_min_height": docker.panel.body.minimumSizeHint().height(),
            "scroll_range": scroll.verticalScrollBar().maximum(),
            "generate_shown": not docker.panel.generate.visibleRegion().isEmpty(),
        }
        docker.hide()

    # A light drag (issue #14): previews of the image in the docker, the canvas left alone until the release
    host.active_document = lambda: doc
    doc.setSelection(Selection())
    activate(doc, person)
    choose(controller, "low-sun-left")  # shadow to the right
    controller.generate()
    wait_for(controller)
    pump(0.5)
    activate(doc, person)
    before, documents = shadow_state(doc, depth), len(k.documents())
    width, height, rgba = host.preview_background(controller.source, 320)
    x0, y0, x1, y1 = OBJ
    right = (x1 + 10, (y0 + y1) // 2, W - 10, y1 + 30)  # where the shadow falls, in document pixels

    def reds(image, w, scale, channels):
        return [
            image[channels * (y * w + x)]
            for y in range(int(right[1] * scale), int(right[3] * scale))
            for x in range(int(right[0] * scale), int(right[2] * scale))
        ]

    shown = doc.projection(0, 0, W, H).convertToFormat(QImage.Format.Format_RGBA8888)
    projected = shown.constBits().asstring(shown.sizeInBytes())
    drag = case["drag"] = {
        "background_size": [width, height],
        "background_under_shadow": [min(reds(rgba, width, width / W, 4)), max(reds(rgba, width, width / W, 4))],
        "canvas_under_shadow_min": min(reds(projected, W, 1.0, 4)),
    }
    previews, start, said = [], len(renders), len(messages)
    controller.previewed.connect(lambda rgb, w, h: previews.append((rgb, w, h)))
    sent = []  # the layer's pixels and rect as the docker hands them to Krita
    host_write = host.write

    def recorded_write(source, pixels, rect, new_step, blend):
        sent.append((pixels, rect))
        return host_write(source, pixels, rect, new_step, blend)

    host.write = recorded_write
    editor = controller.model.light_map.copy()
    for i in range(12):  # a mouse drag, faster than the rest delay
        editor.move(0, 0.25 + 0.01 * i, editor.lights[0].v)
        controller.model.edit_light_map(editor, i == 0, dragging=True)
        pump(0.05)
    pump(0.1)
    drag.update(
        previews=len(previews),
        preview_size=list(previews[-1][1:]) if previews else None,
        preview_under_shadow_min=min(reds(*previews[-1][:2], previews[-1][1] / W, 3)) if previews else None,
        writes_during=len(renders) - start,
        # the drag's start replaced the shadow layer by a copy of itself (its undo step): a new id, the same pixels
        canvas_unchanged_during=pixels_of(shadow_state(doc, depth)) == pixels_of(before),
        replaced_at_start=shadow_state(doc, depth).get("uid") != before["uid"],
        documents_unchanged=len(k.documents()) == documents,
        shadow_visible=all(n.visible() for n in doc.rootNode().childNodes()),
        active=doc.activeNode().name() if doc.activeNode() is not None else None,
    )
    controller.model.edit_light_map(editor, False)  # the release
    wait_for(controller)
    drag["writes_after"] = len(renders) - start
    drag["release_created"] = bool(renders[-1]["created"]) if len(renders) > start else None
    drag["changed_after"] = pixels_of(shadow_state(doc, depth)) != pixels_of(before)
    drag["messages"] = messages[said:]
    # Krita holds exactly the pixels the worker rendered for the release, in the document's depth, and nothing
    # outside their rect
    shadow = next(n for n in doc.rootNode().childNodes() if n.name() == "Shadow: Person")
    pixels, (x, y, w, h) = sent[-1]
    bounds = shadow.bounds()
    drag["release_pixels_exact"] = bytes(shadow.pixelData(x, y, w, h)) == pixels and len(pixels) > 0
    drag["release_within_rect"] = (
        bounds.x() >= x and bounds.y() >= y and bounds.right() < x + w and bounds.bottom() < y + h
    )
    host.write = host_write
    undo = k.action("edit_undo")
    if undo is not None:  # the drag is one replacement: no shadow after one Ctrl+Z, the one before it after two
        undo.trigger()
        doc.waitForDone()
        pump(0.3)
        drag["after_one_undo"] = layer_names(doc)
        undo.trigger()
        doc.waitForDone()
        pump(0.3)
        drag["after_two_undos_is_before"] = shadow_state(doc, depth) == before

    # A black shadow's layer is Normal; in Multiply (a coloured shadow's mode) it composites the same
    shadow_node = next(n for n in doc.rootNode().childNodes() if n.name() == "Shadow: Person")
    modes = case["black_shadow_modes"] = {}
    for mode in ("normal", "multiply"):
        modes[mode] = {"mode": shadow_node.blendingMode()}
        shadow_node.setBlendingMode(mode)
        doc.refreshProjection()
        doc.waitForDone()
        image = doc.projection(0, 0, W, H).convertToFormat(QImage.Format.Format_RGBA8888)
        modes[mode]["reds"] = reds(image.constBits().asstring(image.sizeInBytes()), W, 1.0, 4)
    # a coloured shadow is written as a Multiply layer, which tints what lies under it
    choose(controller, color=(0.2, 0.3, 0.9))
    controller.generate()
    wait_for(controller)
    case["coloured"] = shadow_state(doc, depth)
    engine.shutdown()
    save()


def main(*args):
    try:
        with_window = os.environ.get("SSN_TEST_WINDOW") == "1"
        out["krita"] = Krita.instance().version()
        out["window"] = with_window
        for depth in os.environ.get("SSN_TEST_DEPTHS", "U8,F32").split(","):
            run_case(depth, with_window)
        out["done"] = True
    except Exception:
        out["error"] = traceback.format_exc()
    save()
