"""docs/img/krita-setup.png: the Krita docker's Set up box (the real widget, offscreen Qt grab at the docked
width) as an artist meets it after importing the one-file package: offered, installing, and after a failure
(the message the set-up gives when the package index cannot be reached).

usage: QT_QPA_PLATFORM=offscreen python tools/setup_box_figure.py [--out docs/img/krita-setup.png]
"""

from __future__ import annotations

import argparse
import json
import os
import sys
import tempfile
from pathlib import Path

import numpy as np
from PIL import Image
from krita_docker_figure import docked_app

from ssn_engine import __version__
from ssn_engine.host_kit import engine_setup, setup_failures


class Job:
    """Stands in for the set-up thread (SetupBox.start makes one): the events a real run reports at that point."""

    events_next: list[engine_setup.SetupEvent] = []

    def __init__(self, setup: engine_setup.EngineSetup) -> None:
        self.running = True

    def start(self) -> Job:
        return self

    def events(self) -> list[engine_setup.SetupEvent]:
        events, Job.events_next = Job.events_next, []
        return events


def grab(widget, app) -> np.ndarray:
    widget.resize(340, widget.sizeHint().height())
    widget.show()
    for _ in range(10):
        app.processEvents()
    image = widget.grab().toImage().convertToFormat(4)  # QImage.Format_RGB32
    w, h = image.width(), image.height()
    data = np.frombuffer(image.constBits().asstring(h * image.bytesPerLine()), np.uint8).reshape(h, -1, 4)
    return data[:, :w, [2, 1, 0]]


def main(argv: list[str] | None = None) -> int:
    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    p.add_argument("--out", default="docs/img/krita-setup.png")
    args = p.parse_args(argv)
    app = docked_app()
    from plugin_krita.ssn_shadow.ui import setup_box

    with tempfile.TemporaryDirectory() as tmp:
        plugin, data = Path(tmp) / "ssn_shadow", Path(tmp) / "data"
        plugin.mkdir()
        wheel = f"ssn_shadow-{__version__}-py3-none-any.whl"
        (plugin / "setup.json").write_text(json.dumps({"version": __version__, "wheel": wheel, "sha256": "0" * 64}))
        os.environ[engine_setup.DATA_ENV] = str(data)
        shots = []
        box = setup_box.SetupBox(plugin)
        shots.append(grab(box, app))  # offered
        data.mkdir()
        (data / "setup.log").write_text("")
        setup_box.engine_setup.SetupJob = Job  # Set up pressed: the box's own start, with the stand-in thread
        box.setup_button.click()
        Job.events_next = [engine_setup.SetupEvent(0.41, "Getting scipy>=1.9...")]
        box._poll()
        shots.append(grab(box, app))  # installing
        env = {"PIP_INDEX_URL": setup_failures.DEFAULT_INDEX}
        failed = setup_failures.explain_failure("NewConnectionError", data, env, "Installing the engine")
        Job.events_next = [engine_setup.SetupEvent(0.0, failed, done=True, error=failed)]
        box._poll()
        shots.append(grab(box, app))  # failed
    height = max(s.shape[0] for s in shots)
    gap = np.full((height, 12, 3), 255, np.uint8)
    padded = [np.pad(s, ((0, height - s.shape[0]), (0, 0), (0, 0)), constant_values=255) for s in shots]
    row = np.concatenate([padded[0], gap, padded[1], gap, padded[2]], axis=1)
    Image.fromarray(row).save(args.out)
    print(f"wrote {args.out} ({row.shape[1]} x {row.shape[0]})")
    return 0


if __name__ == "__main__":
    sys.exit(main())
