"""Runs inside real Krita (kritarunner): a light's size set in the docker's Size box, and the shadow it makes.

``kritarunner -s krita_size_driver -f main`` (on a virtual X screen) shows the docker in a Krita window, picks
the Sun preset, sets the light's size to 12 and then 0.53 degrees by typing into the Size box, presses Generate
after each and writes, per size, what the box shows, the light map the docker holds and how crisp the shadow
layer is, to $SSN_TEST_RESULT.
"""

import os

from krita_docker_driver import H, W, add_docker, bind_to, person_in_window, recording, wait_idle
from krita_driver import alpha_plane, pump
from PyQt5.QtCore import Qt
from PyQt5.QtTest import QTest
from PyQt5.QtWidgets import QDockWidget

RESULT = os.environ.get("SSN_TEST_RESULT", "/tmp/ssn_krita_size.json")
out: dict = {"sizes": {}}


def crispness(alpha):
    """The shadow's gradient energy per unit of darkness: squared steps between neighbouring pixels of its alpha
    over the alpha's sum."""
    energy = sum((alpha[i + 1] - alpha[i]) ** 2 for y in range(H) for i in range(y * W, y * W + W - 1))
    energy += sum((alpha[i + W] - alpha[i]) ** 2 for i in range(W * (H - 1)))
    return energy / max(1e-9, sum(alpha))


def main(*args):
    with recording(out, RESULT):
        doc, person, qwin = person_in_window("ssn-size", 160, 120, 60, 160)
        qwin.show()
        docker = add_docker(qwin)
        pump(1.5)
        controller, panel = bind_to(docker, doc, person)
        panel.presets.setCurrentIndex(panel.presets.findData("sun"))
        panel.presets.activated.emit(panel.presets.currentIndex())
        pump(0.2)
        out["preset_size"] = panel.size_box.value()
        for text in ("12", "0.53"):
            box = panel.size_box
            box.setFocus()
            box.selectAll()
            QTest.keyClicks(box, text)  # as a user types it
            QTest.keyClick(box, Qt.Key.Key_Return)
            pump(0.2)
            panel.generate.click()
            wait_idle(controller)
            names = [n.name() for n in doc.rootNode().childNodes()]
            shadow = doc.rootNode().childNodes()[names.index("Shadow: Person")]
            alpha = alpha_plane(shadow, "U8")
            out["sizes"][text] = {
                "box": box.value(),
                "lights": controller.model.light_map.to_dict()["lights"],
                "map_lights": panel.map_widget.light_map.to_dict()["lights"],
                "darkness": round(sum(alpha), 1),
                "crispness": round(crispness(alpha), 5),
            }
        out["messages"] = list(controller.model.status)
        out["docks"] = [d.objectName() for d in qwin.findChildren(QDockWidget)][:3]
        docker.engine.shutdown()
