"""Runs inside real Krita (kritarunner): the docker's settings saved in a .kra and read back by a fresh Krita.

``kritarunner -s krita_settings_driver -f save`` sets the settings through the docker's panel, checks what
that did to the document (pixels, undo, modified), saves the .kra ($SSN_TEST_KRA) and closes it; ``-f reopen``
(a new Krita process) opens the .kra and reads what the docker's panel shows. Each writes $SSN_TEST_RESULT.
"""

import hashlib
import json
import os
import time
import traceback

from krita import Krita
from PyQt5.QtWidgets import QApplication

RESULT = os.environ.get("SSN_TEST_RESULT", "/tmp/ssn_krita_settings.json")
KRA = os.environ.get("SSN_TEST_KRA", "/tmp/ssn_settings.kra")
W, H = 320, 240
out = {"log": []}


def save_result():
    with open(RESULT, "w") as f:
        json.dump(out, f, indent=1)


def pump(seconds):
    deadline = time.monotonic() + seconds
    while time.monotonic() < deadline:
        QApplication.processEvents()
        time.sleep(0.01)


def pixels(doc):
    """A digest of each layer's pixels, by name (what the user painted)."""
    return {n.name(): hashlib.sha1(bytes(n.pixelData(0, 0, W, H))).hexdigest() for n in doc.rootNode().childNodes()}


def wait_for(controller, timeout_s=90.0):
    """Until the controller is idle (its render written)."""
    deadline = time.monotonic() + timeout_s
    pump(0.1)
    while controller.busy and time.monotonic() < deadline:
        pump(0.05)
    pump(0.3)


def shadow_top(doc):
    """The topmost canvas row of the shadow layer whose alpha is above 5 % of its darkest (None: no layer)."""
    shadow = next((n for n in doc.rootNode().childNodes() if n.name().startswith("Shadow")), None)
    if shadow is None:
        return None
    alpha = bytes(shadow.pixelData(0, 0, W, H))[3::4]
    darkest = max(alpha)
    return next((r for r in range(H) if max(alpha[r * W : (r + 1) * W]) > 0.05 * darkest), None)


def docker_parts(doc):
    """The docker's parts as SoftShadowDocker builds them, on ``doc``."""
    from ssn_shadow.adapters.host import KritaHost
    from ssn_shadow.controller import ShadowController
    from ssn_shadow.engine import EngineProcess
    from ssn_shadow.persistence import DocumentModels
    from ssn_shadow.ui.panel import ShadowPanel

    host = KritaHost(Krita.instance())
    host.active_document = lambda: doc
    models = DocumentModels(host)
    controller = ShadowController(EngineProcess(), host, models.model_for(doc))
    return controller, ShadowPanel(controller)


def shown(panel):
    """What the panel shows, and the model behind it."""
    m = panel.model
    return {
        "panel": {
            "light_map": panel.map_widget.light_map.to_dict(),
            "use_horizon": panel.use_horizon.isChecked(),
            "horizon": panel.horizon.value(),
            "fov": panel.fov.value(),
            "opacity": panel.opacity.value(),
            "ao_strength": panel.ao_strength.value(),
            "colour": panel.color_button.styleSheet(),
            "lift": panel.lift_box.value(),
            "thickness": panel.thickness.value(),
            "thickness_label": panel.thickness_label.text(),
        },
        "model": {
            "light_map": m.light_map.to_dict(),
            "camera": m.camera,
            "color": list(m.color),
            "opacity": m.opacity,
            "ao_edits": m.ao_edit_list(),
            "geometry": [m.lift, m.thickness],
        },
        "status": list(m.status),
    }


def save(*args):
    try:
        k = Krita.instance()
        doc = k.createDocument(W, H, "ssn-settings", "RGBA", "U8", "", 72.0)
        window = k.openWindow()
        window.addView(doc)
        person = doc.createNode("Person", "paintlayer")
        person.setPixelData(bytes([40, 90, 200, 255]) * (80 * 120), 120, 60, 80, 120)
        doc.rootNode().addChildNode(person, doc.rootNode().childNodes()[0])
        doc.waitForDone()
        pump(0.5)
        undo = k.action("edit_undo")
        out["undo_before"] = [undo.text(), undo.isEnabled()] if undo is not None else None
        out["pixels_before"] = pixels(doc)
        controller, panel = docker_parts(doc)
        out["shown_new"] = shown(panel)

        # the user's settings, through the panel's widgets (the colour dialog aside)
        panel.presets.setCurrentIndex(panel.presets.findData("two-lights"))
        panel.presets.activated.emit(panel.presets.currentIndex())
        doc.setHorizontalGuides([123.0])
        panel.from_guide.click()
        panel.fov.setValue(58)
        panel.fov.editingFinished.emit()
        panel.opacity.setValue(40)
        panel.model.color = (0.2, 0.3, 0.9)
        panel.grow.click()
        panel.ao_preview.brushed.emit(0.5, 0.8, True)
        panel.ao_preview.brushed.emit(0.52, 0.8, False)
        panel.ao_strength.setValue(150)
        panel.lift_box.setValue(40)  # the Geometry section: lifted 40 px, thickness 1.5
        panel.thickness.setValue(150)
        doc.waitForDone()
        pump(0.5)

        out["modified_after_settings"] = doc.modified()
        out["undo_after"] = [undo.text(), undo.isEnabled()] if undo is not None else None
        out["pixels_after_settings"] = pixels(doc)
        out["shown_set"] = shown(panel)
        out["saved"] = doc.saveAs(KRA)
        out["modified_after_save"] = doc.modified()
        out["closed"] = doc.close()
        out["done"] = True
    except Exception:
        out["error"] = traceback.format_exc()
    save_result()


def reopen(*args):
    try:
        k = Krita.instance()
        doc = k.openDocument(KRA)
        out["opened"] = doc is not None
        window = k.openWindow()
        window.addView(doc)
        doc.waitForDone()
        pump(0.5)
        out["pixels"] = pixels(doc)
        controller, panel = docker_parts(doc)
        out["shown"] = shown(panel)
        out["modified_after_reading"] = doc.modified()

        # the docker itself, on the active document: it shows that document's settings, the same model at
        # each view change (Krita hands out a new Document wrapper each time)
        from ssn_shadow.docker import SoftShadowDocker

        out["active_is_opened"] = k.activeDocument() == doc
        docker = SoftShadowDocker()
        first = docker.controller.model
        docker.canvasChanged(None)
        out["docker_same_model"] = docker.controller.model is first
        out["docker_shown"] = shown(docker.panel)
        docker.engine.shutdown()

        # the reopened lift casts: Generate (a high sun, behind the object: its shadow comes towards the viewer),
        # then the lift box set to 0, live: the shadow's top row with and without the lift
        person = next(n for n in doc.rootNode().childNodes() if n.name() == "Person")
        doc.setActiveNode(person)
        pump(0.5)
        from ssn_shadow.shared import light_map as lm

        controller.live = False
        controller.model.light_map = lm.preset("high-sun")
        controller.live = True
        controller.generate()
        wait_for(controller)
        out["lifted"] = {"top": shadow_top(doc), "status": list(controller.model.status)}
        panel.lift_box.setValue(0)
        wait_for(controller)
        out["resting"] = {"top": shadow_top(doc), "status": list(controller.model.status)}
        out["lift_after"] = controller.model.lift
        controller.engine.shutdown()
        doc.close()
        out["done"] = True
    except Exception:
        out["error"] = traceback.format_exc()
    save_result()
