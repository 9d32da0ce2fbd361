"""docs/img/krita-docker.png: the Krita docker's panel at the width it gets docked in a 1366 x 768 Krita window
(340 px, Krita's 8 pt UI font), all of it (docked, the lower part scrolls), with the sample pawn's AO and the
live preview of a light drag from the real engine, and the horizon set from a guide (offscreen Qt grab); then
docs/img/krita-camera-read.png: its Camera box with the horizon unticked, showing the camera the shipped model
read from the pawn's outline.

usage: QT_QPA_PLATFORM=offscreen python tools/krita_docker_figure.py [--out docs/img/krita-docker.png]
    [--camera-out docs/img/krita-camera-read.png]
"""

from __future__ import annotations

import argparse
import sys

import numpy as np
from PIL import Image
from PyQt5.QtWidgets import QApplication

from plugin_krita.ssn_shadow.controller import PREVIEW_SIDE, ShadowController
from plugin_krita.ssn_shadow.ui.panel import ShadowPanel
from ssn_engine.methods import load_method
from ssn_engine.host_kit import camera_rules
from ssn_engine.compositing import over, preview_image
from ssn_engine.samples import pawn_cutout, studio_background
from ssn_engine.session import ShadowSession


class Idle:
    """An engine that is never asked anything (the figure shows a state, not a run)."""

    def request(self, *args, **kwargs):
        return 0


class Host:
    class Document:
        def fileName(self):  # noqa: N802 (Krita's API)
            return "pawn.kra"

        def horizontalGuides(self):  # noqa: N802 (Krita's API)
            return [520.0]

    def active_document(self):
        return self.Document()

    def horizontal_guides(self, document):
        return document.horizontalGuides()


def docked_app() -> QApplication:
    """The Qt application with Krita's 8 pt UI font, the docker's widgets drawn as they are docked."""
    app = QApplication.instance() or QApplication(sys.argv)
    font = app.font()
    font.setPointSizeF(8.0)
    app.setFont(font)
    return app


def main(argv: list[str] | None = None) -> int:
    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    p.add_argument("--out", default="docs/img/krita-docker.png")
    p.add_argument("--camera-out", default="docs/img/krita-camera-read.png")
    args = p.parse_args(argv)
    app = docked_app()
    pawn = pawn_cutout()
    session = ShadowSession(pawn[..., 3], load_method("auto").method)
    u8 = lambda a: np.rint(np.clip(a, 0, 1) * 255).astype(np.uint8).tobytes()  # noqa: E731
    controller = ShadowController(Idle(), Host())
    panel = ShadowPanel(controller)
    panel.ao_preview.set_images(u8(session.ao), u8(session.mask), session.mask.shape[0])
    panel.from_guide.click()  # the horizon from the sample's guide (row 520, where its floor meets the wall)
    # The live preview of a light drag, as the worker's preview command draws it
    height, width = pawn.shape[:2]
    pw, ph, _ = camera_rules.preview_size(width, height, PREVIEW_SIDE)
    framing = session.framing.scaled(pw / width)
    image = Image.fromarray(over(studio_background(), pawn)).resize((pw, ph), Image.Resampling.LANCZOS)
    shadow = session.render(controller.model.light_map, framing)
    shown = preview_image(np.asarray(image), shadow, session.cover(framing), horizon=520.0 * pw / width)
    panel.preview.set_image(shown.tobytes(), pw, ph)
    panel.resize(340, 900)
    panel.show()
    for _ in range(40):  # tall enough that the controls do not scroll: the whole panel
        app.processEvents()
        if panel.scroll.verticalScrollBar().maximum() == 0:
            break
        panel.resize(340, panel.height() + panel.scroll.verticalScrollBar().maximum())
    for _ in range(10):
        app.processEvents()
    panel.grab().save(args.out)
    print(f"wrote {args.out}", file=sys.stderr)
    panel.use_horizon.setChecked(False)  # blind: the worker's set_cutout reply carries the camera it read
    controller.model.report_camera_read(session.camera_read)
    for _ in range(10):
        app.processEvents()
    panel.use_horizon.parentWidget().grab().save(args.camera_out)
    print(f"wrote {args.camera_out} ({session.camera_read})", file=sys.stderr)
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
