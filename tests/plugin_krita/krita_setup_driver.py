"""Runs inside real Krita (kritarunner): the packaged plug-in, imported as Krita's importer does, sets up its engine.

``kritarunner -s krita_setup_driver -f main`` with only the imported plug-in on PYTHONPATH (no engine anywhere):
the docker shows Set up; a first Set up is cancelled while it installs, a second resumes it; then Generate makes
a shadow with the engine just set up. Writes $SSN_TEST_RESULT.
"""

import os
import time

from krita_docker_driver import add_docker, bind_to, person_in_window, recording, wait_idle
from krita_driver import pump

RESULT = os.environ.get("SSN_TEST_RESULT", "/tmp/ssn_krita_setup.json")
SETUP_TIMEOUT_S = float(os.environ.get("SSN_TEST_SETUP_TIMEOUT", "900"))
out = {"log": []}


def wait_setup(box, stop_at=None):
    """Pump until the box's set-up ends (or its progress reaches ``stop_at``); the texts it showed."""
    texts = []
    deadline = time.monotonic() + SETUP_TIMEOUT_S
    while box.job is not None and (box.job.running or box._timer.isActive()) and time.monotonic() < deadline:
        pump(0.1)
        if box.message.text() not in texts:
            texts.append(box.message.text())
        if stop_at is not None and box.progress.value() >= stop_at:
            break
    return texts


def main(*args):
    with recording(out, RESULT):
        try:
            import ssn_engine  # noqa: F401

            out["engine_importable_in_krita"] = True
        except ImportError:
            out["engine_importable_in_krita"] = False
        doc, person, qwin = person_in_window("ssn-setup", 200, 90, 80, 180)
        qwin.show()
        pump(1.0)
        docker = add_docker(qwin)
        pump(1.0)
        box = docker.setup_box
        out["before"] = {"shown": box.isVisible(), "text": box.message.text(), "button": box.setup_button.text()}
        controller, panel = bind_to(docker, doc, person)
        panel.generate.click()
        wait_idle(controller, 30)
        out["generate_before"] = list(controller.model.status)

        box.setup_button.click()
        out["first"] = wait_setup(box, stop_at=15)  # installing: cancel it
        box.cancel_button.click()
        wait_setup(box)
        out["cancelled"] = {"text": box.message.text(), "button": box.setup_button.text(), "shown": box.isVisible()}

        started = time.monotonic()
        box.setup_button.click()
        out["second"] = wait_setup(box)
        out["setup_s"] = time.monotonic() - started
        out["after"] = {"shown": box.isVisible(), "status": list(controller.model.status)}

        panel.generate.click()
        wait_idle(controller, 180)
        out["names"] = [n.name() for n in doc.rootNode().childNodes()]
        out["messages"] = list(controller.model.status)
        command = docker.engine._command
        out["engine_command"] = list(command.command) if command is not None else []
        docker.engine.shutdown()
