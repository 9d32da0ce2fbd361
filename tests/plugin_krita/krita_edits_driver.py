"""Runs inside real Krita (kritarunner): the docker as Krita makes it (its factory registered as the plug-in manager
does, the docker built by the window), after edits outside the docker: the cutout painted on, a step chosen in
the Undo History docker, a document closed. Writes $SSN_TEST_RESULT.

``kritarunner -s krita_edits_driver -f main`` on a virtual X screen (the undo history exists only with a window).
"""

import hashlib
import os
import time

from krita import Krita
from krita_docker_driver import recording, wait_idle
from krita_driver import pump
from PyQt5.QtCore import Qt
from PyQt5.QtTest import QTest
from PyQt5.QtWidgets import QDockWidget, QListView

RESULT = os.environ.get("SSN_TEST_RESULT", "/tmp/ssn_krita_edits.json")
W, H = 480, 360
out = {"log": []}


def docker_of(window):
    return next(d for d in window.qwindow().findChildren(QDockWidget) if d.objectName() == "ssn_shadow_docker")


def shadow_digest(doc):
    """A digest of the shadow layer's pixels (None: no shadow layer)."""
    shadow = next((n for n in doc.rootNode().childNodes() if n.name() == "Shadow: Person"), None)
    return hashlib.sha1(bytes(shadow.pixelData(0, 0, W, H))).hexdigest() if shadow is not None else None


def shadow_uid(doc):
    """The shadow layer's unique id (None: no shadow layer)."""
    shadow = next((n for n in doc.rootNode().childNodes() if n.name() == "Shadow: Person"), None)
    return shadow.uniqueId().toString() if shadow is not None else None


def active_name(doc):
    node = doc.activeNode()
    return node.name() if node is not None else None


def choose(controller, preset, live=True):
    """The preset as the panel's preset box sets it (one edit, an undo step of its own)."""
    from ssn_shadow.shared import light_map as lm

    controller.live = live
    controller.model.light_map = lm.preset(preset)


def edit_in_box(doc, action, box):
    """Krita's ``action`` (Edit > Clear, Fill with Foreground Color) on the active layer within ``box`` (x, y, w,
    h), as a user does: a selection made, the edit, the selection gone; each an undo command (the docker reads the
    cutout again only after one: Node.setPixelData makes none)."""
    from krita import Selection

    selection = Selection()
    selection.select(*box, 255)
    doc.setSelection(selection)
    pump(0.3)
    Krita.instance().action(action).trigger()
    doc.waitForDone()
    pump(0.3)
    Krita.instance().action("deselect").trigger()
    doc.waitForDone()
    pump(0.3)


def history_step(window, rows_back):
    """Click the row ``rows_back`` above (negative: below) the current one in the window's Undo History docker,
    as the user does: Krita goes to that step without its undo and redo actions."""
    dock = next(d for d in window.qwindow().findChildren(QDockWidget) if d.objectName() == "History")
    dock.show()
    pump(0.3)
    view = dock.findChild(QListView)
    index = view.model().index(view.currentIndex().row() - rows_back, 0)
    QTest.mouseClick(
        view.viewport(), Qt.MouseButton.LeftButton, Qt.KeyboardModifier.NoModifier, view.visualRect(index).center()
    )
    pump(1.5)
    return [view.model().index(r, 0).data() for r in range(view.model().rowCount())]


def main(*args):
    with recording(out, RESULT):
        import ssn_shadow  # noqa: F401  (registers the docker's factory, as Krita's plug-in manager does)

        k = Krita.instance()
        doc = k.createDocument(W, H, "ssn-edits", "RGBA", "U8", "", 72.0)
        person = doc.createNode("Person", "paintlayer")
        person.setPixelData(bytes([200, 90, 40, 255]) * (80 * 180), 200, 90, 80, 180)
        doc.rootNode().addChildNode(person, doc.rootNode().childNodes()[0])
        window = k.openWindow()
        window.addView(doc)
        window.qwindow().resize(1200, 760)
        window.qwindow().show()
        pump(2.0)
        docker = docker_of(window)
        docker.show()
        doc.setActiveNode(person)
        pump(0.5)
        controller, panel = docker.controller, docker.panel

        # 1. The cutout painted on after Generate: the next light change casts the new cutout's shadow
        choose(controller, "low-sun-left", live=False)
        panel.generate.click()
        wait_idle(controller)
        whole = shadow_digest(doc)
        keys = [controller._cutout_key]  # the cutout the worker renders from: its alpha's digest
        edit_in_box(doc, "clear", (200, 180, 80, 90))  # the lower half erased
        choose(controller, "low-sun-right")  # Live: rendered at once
        wait_idle(controller)
        by_light = shadow_digest(doc)
        keys.append(controller._cutout_key)
        panel.generate.click()  # what Generate casts from the layer as it is now, with that light
        wait_idle(controller)
        out["stale"] = {
            "whole": whole,
            "by_light": by_light,
            "by_generate": shadow_digest(doc),
            "messages": list(controller.model.status),
            "keys": keys + [controller._cutout_key],
        }
        # ... and after more alpha painted, a light drag's release casts it too
        edit_in_box(doc, "fill_selection_foreground_color", (240, 180, 40, 90))
        editor = controller.model.light_map.copy()
        for i in range(6):
            editor.move(0, 0.3 + 0.02 * i, editor.lights[0].v)
            controller.model.edit_light_map(editor, i == 0, dragging=True)
            pump(0.05)
        controller.model.edit_light_map(editor, False)
        wait_idle(controller)
        dragged = shadow_digest(doc)
        keys.append(controller._cutout_key)
        panel.generate.click()
        wait_idle(controller)
        out["stale"].update(
            dragged=dragged, dragged_by_generate=shadow_digest(doc), drag_keys=keys[-1:] + [controller._cutout_key]
        )

        # 2. A step chosen in the Undo History docker: two back (the last Generate's replacement undone: its
        # shadow goes, the one before comes back), then both again; the cutout's layer stays active
        doc.setActiveNode(person)
        pump(0.5)
        before = shadow_uid(doc)
        rows = history_step(window, 2)
        back = {"active": active_name(doc), "rows": rows, "shadow_changed": shadow_uid(doc) not in (None, before)}
        history_step(window, -2)
        out["history"] = {
            "back": back,
            "forward": {"active": active_name(doc), "shadow_is_last": shadow_uid(doc) == before},
        }

        # 3. A document with a message in its own window, closed: the docker no longer shows its message
        grey = k.createDocument(W, H, "ssn-grey", "GRAYA", "U8", "", 72.0)
        other = k.openWindow()
        other.addView(grey)
        other.qwindow().show()
        pump(1.5)
        other_docker = docker_of(other)
        other_docker.show()
        pump(0.5)
        # the virtual screen has no window manager to activate the new window: its docker is told its document
        other_docker.controller.host.active_document = lambda: grey
        other_docker.canvasChanged(None)
        other_docker.panel.generate.click()
        pump(0.5)
        closing = {"message_before": other_docker.panel.message.text()}
        t = time.monotonic()
        grey.close()
        pump(1.0)
        closing.update(
            message_after=other_docker.panel.message.text(),
            open_documents=[d.name() for d in k.documents()],
            seconds=round(time.monotonic() - t, 2),
        )
        out["closing"] = closing
        docker.engine.shutdown()
        other_docker.engine.shutdown()
