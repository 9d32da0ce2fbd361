"""Runs inside real Krita (kritarunner): the docker in a Krita window on a 1366 x 768 screen, and Krita's undo.

``kritarunner -s krita_docker_driver -f main`` (a fresh profile, on a virtual 1366 x 768 X screen) shows a
window of a fresh profile's size with the docker at Krita's default place and width, generates two shadows
through the docker's panel and undoes them with Krita's undo action; it writes $SSN_TEST_RESULT.
"""

import contextlib
import json
import os
import time
import traceback

from krita import Krita
from PyQt5.QtCore import Qt
from krita_driver import pump
from PyQt5.QtWidgets import QApplication, QDockWidget

RESULT = os.environ.get("SSN_TEST_RESULT", "/tmp/ssn_krita_docker.json")
W, H = 480, 360
NARROW = 260  # pixels: a dock column narrower than Krita's default
SHORT = (262, 180)  # pixels: the docker in Krita's default workspace on a 1366 x 768 screen
out = {"log": []}


@contextlib.contextmanager
def recording(out, path):
    """Run the driver's block, then write ``out`` to ``path`` as JSON: with "done" where the block ended, with the
    traceback as "error" where it raised."""
    try:
        yield
        out["done"] = True
    except Exception:
        out["error"] = traceback.format_exc()
    with open(path, "w") as f:
        json.dump(out, f, indent=1)


def wait_idle(controller, timeout_s=120.0):
    deadline = time.monotonic() + timeout_s
    pump(0.2)
    while controller.busy and time.monotonic() < deadline:
        pump(0.05)
    pump(0.5)


def person_in_window(name, x, y, w, h):
    """A W x H U8 document named ``name`` in a Krita window, with a layer "Person" opaque over the w x h
    rectangle at x, y: (the document, the layer, the window's QMainWindow)."""
    doc = Krita.instance().createDocument(W, H, name, "RGBA", "U8", "", 72.0)
    person = doc.createNode("Person", "paintlayer")
    person.setPixelData(bytes([200, 90, 40, 255]) * (w * h), x, y, w, h)
    doc.rootNode().addChildNode(person, doc.rootNode().childNodes()[0])
    window = Krita.instance().openWindow()
    window.addView(doc)
    return doc, person, window.qwindow()


def add_docker(qwin):
    """The Soft Shadow docker added to the window where Krita puts a new docker (the right dock column)."""
    from ssn_shadow.docker import DOCKER_ID, SoftShadowDocker

    docker = SoftShadowDocker()
    docker.setObjectName(DOCKER_ID)
    qwin.addDockWidget(Qt.DockWidgetArea.RightDockWidgetArea, docker)
    docker.show()
    return docker


def bind_to(docker, doc, person):
    """The docker's controller and panel on ``doc``'s model, its source ``person`` (kritarunner's window may not
    be the active one); Live off: the driver presses Generate."""
    controller, panel = docker.controller, docker.panel
    doc.setActiveNode(person)
    pump(0.5)
    controller.host.active_document = lambda: doc
    controller.set_model(docker.models.model_for(doc))
    panel.show_model(controller.model)
    controller.live = False
    return controller, panel


def short_dock(docker):
    """The docker's height and what its panel shows without scrolling: the map whole within the scroll area's
    viewport, Generate within the panel."""
    panel = docker.panel
    viewport = panel.scroll.viewport()
    top = panel.map_widget.mapTo(viewport, panel.map_widget.rect().topLeft())
    bottom = panel.map_widget.mapTo(viewport, panel.map_widget.rect().bottomRight())
    generate = panel.generate.mapTo(panel, panel.generate.rect().bottomRight())
    return {
        "docker": [docker.width(), docker.height()],
        "viewport_height": viewport.height(),
        "body_height": panel.body.height(),
        "scrolled": panel.scroll.verticalScrollBar().value(),
        "map_in_view": viewport.rect().contains(top) and viewport.rect().contains(bottom),
        "map_height": panel.map_widget.height(),
        "generate_in_view": panel.rect().contains(generate) and not panel.generate.visibleRegion().isEmpty(),
        "open": {name: section.is_open() for name, section in getattr(panel, "sections", {}).items()},
    }


def main(*args):
    with recording(out, RESULT):
        from ssn_shadow.shared import light_map as lm

        doc, person, qwin = person_in_window("ssn-docker", 200, 90, 80, 180)
        # A profile without a saved window geometry: Krita 5.1 opens its window at two thirds of a screen wider
        # than 1024 px, centred (KisMainWindow::initializeGeometry); the virtual screen has no window manager.
        screen = QApplication.primaryScreen().availableGeometry()
        w, h = screen.width() * 2 // 3, screen.height() * 2 // 3
        qwin.setGeometry(screen.x() + (screen.width() - w) // 2, screen.y() + (screen.height() - h) // 2, w, h)
        qwin.show()
        pump(2.0)
        layers = next(d for d in qwin.findChildren(QDockWidget) if d.objectName() == "KisLayerBox")
        default_width = layers.width()  # the right dock column of a fresh profile
        docker = add_docker(qwin)
        pump(1.0)
        widened = docker.width()
        # Krita restores its dock column's width (its workspace) rather than widening it for a new docker
        qwin.resizeDocks([docker], [default_width], Qt.Orientation.Horizontal)
        pump(2.0)
        panel = docker.panel
        out["layout"] = {
            "screen": list(QApplication.primaryScreen().availableGeometry().getRect()),
            "window": list(qwin.geometry().getRect()),
            "default_width": default_width,
            "widened_to": widened,
            "docker_width": docker.width(),
            "layers_docker_width": layers.width(),
            "viewport_width": panel.scroll.viewport().width(),
            "body_min_width": panel.body.minimumSizeHint().width(),
            "horizontal_scroll_bar": panel.scroll.horizontalScrollBar().isVisible(),
            "map_right": panel.map_widget.mapTo(panel.scroll.viewport(), panel.map_widget.rect().topRight()).x(),
            "presets_right": panel.presets.mapTo(panel.scroll.viewport(), panel.presets.rect().topRight()).x(),
            "generate_visible": panel.generate.isVisible() and not panel.generate.visibleRegion().isEmpty(),
        }
        qwin.resizeDocks([docker], [NARROW], Qt.Orientation.Horizontal)  # the user narrows the dock column
        pump(1.0)
        out["narrow"] = {
            "docker_width": docker.width(),
            "viewport_width": panel.scroll.viewport().width(),
            "horizontal_scroll_bar": panel.scroll.horizontalScrollBar().isVisible(),
            "map_right": panel.map_widget.mapTo(panel.scroll.viewport(), panel.map_widget.rect().topRight()).x(),
        }
        out["default_height"] = short_dock(docker)  # the docker where Krita put it, stacked under the others
        # Krita's default workspace on a 1366 x 768 screen: the docker 262 x about 180, stacked under the others
        qwin.resizeDocks([docker], [SHORT[0]], Qt.Orientation.Horizontal)
        qwin.resizeDocks([docker], [SHORT[1]], Qt.Orientation.Vertical)
        pump(1.0)
        out["short"] = short_dock(docker)
        qwin.resizeDocks([docker], [default_width], Qt.Orientation.Horizontal)
        pump(0.5)

        controller, panel = bind_to(docker, doc, person)
        controller.watch_history()
        controller.model.light_map = lm.preset("low-sun-left")
        panel.generate.click()
        wait_idle(controller)
        first = controller.model.light_map.to_dict()
        controller.model.light_map = lm.preset("low-sun-right")
        panel.generate.click()
        wait_idle(controller)
        doc.setActiveNode(person)
        pump(0.5)
        undo = Krita.instance().action("edit_undo")
        steps = out["undo"] = []
        for _ in range(2):  # the new shadow goes, then the first one comes back
            text = undo.text()
            undo.trigger()
            doc.waitForDone()
            pump(1.5)
            active = doc.activeNode()
            steps.append(
                {
                    "text": text,
                    "names": [n.name() for n in doc.rootNode().childNodes()],
                    "active": active.name() if active is not None else None,
                    "light_map": controller.model.light_map.to_dict(),
                    "preset": panel.presets.currentText(),
                }
            )
        out["first_light_map"] = first
        # the Intensity box: it shows the selected light's intensity, and a value typed in it is the light's
        shown = panel.intensity_box.value()
        panel.intensity_box.setValue(1.5)
        out["intensity"] = {"shown": shown, "light": controller.model.light_map.lights[0].intensity}
        out["messages"] = list(controller.model.status)
        docker.engine.shutdown()
