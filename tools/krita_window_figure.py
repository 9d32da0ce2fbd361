"""docs/img/krita-window.png: real Krita in a 1366 x 768 window, the Soft Shadow docker docked on the right, the
sample pawn with its shadow, the horizon taken from a guide; krita-window-camera.png: the same with the docker
scrolled to its Camera group (issue #14's screenshots).

usage: python tools/krita_window_figure.py [--out docs/img/krita-window.png]

Needs Debian's krita (kritarunner) and xvfb-run. This script starts Krita on a 1366 x 768 virtual screen and
runs its own ``inside`` function there (Krita's Python: no numpy), which grabs the screen.
"""

from __future__ import annotations

import os
import sys
import time
from pathlib import Path

W, H = 1200, 900  # the sample's canvas
HORIZON = 520  # the sample background's floor line


def inside(*_args: object) -> None:  # pragma: no cover - runs in Krita (kritarunner passes its arguments)
    """Build the document, dock the docker, generate, and grab the screen into $SSN_FIGURE_OUT."""
    from krita import Krita
    from PyQt5.QtCore import QEventLoop, Qt, QTimer
    from PyQt5.QtWidgets import QApplication, QDockWidget
    from ssn_shadow.docker import SoftShadowDocker

    work = Path(os.environ["SSN_FIGURE_WORK"])
    say = lambda text: print(f"figure: {text}", file=sys.stderr, flush=True)  # noqa: E731
    app = Krita.instance()
    doc = app.createDocument(W, H, "pawn", "RGBA", "U8", "", 72.0)
    root = doc.rootNode()
    background = root.childNodes()[0]
    background.setPixelData((work / "background.bgra").read_bytes(), 0, 0, W, H)
    pawn = doc.createNode("Pawn", "paintlayer")
    pawn.setPixelData((work / "pawn.bgra").read_bytes(), 0, 0, W, H)
    root.addChildNode(pawn, background)
    doc.setHorizontalGuides([float(HORIZON)])
    doc.setGuidesVisible(True)
    window = app.openWindow()
    window.addView(doc)
    main = window.qwindow()
    main.resize(1366, 768)
    main.show()
    for other in main.findChildren(QDockWidget):  # a clean workspace: the Layers docker and this one
        if other.objectName() != "KisLayerBox":
            other.hide()
    docker = SoftShadowDocker()
    main.addDockWidget(Qt.DockWidgetArea.RightDockWidgetArea, docker)
    docker.show()
    doc.setActiveNode(pawn)
    doc.waitForDone()

    def wait(seconds: float) -> None:
        loop = QEventLoop()
        QTimer.singleShot(int(seconds * 1000), loop.quit)
        loop.exec_()

    say("window up")
    wait(2.0)
    say("waited")
    docker.controller.host.active_document = lambda: doc
    docker.panel.from_guide.click()
    docker.panel.presets.setCurrentIndex(docker.panel.presets.findData("low-sun-left"))
    docker.panel.presets.activated.emit(docker.panel.presets.currentIndex())
    say("generate")
    docker.panel.generate.click()
    deadline = time.monotonic() + 120
    while (docker.controller.busy or docker.controller.renders == 0) and time.monotonic() < deadline:
        wait(0.2)
    say(f"rendered {docker.controller.renders}")
    # A light dragged on the map, as with the mouse: the docker previews, the layer follows on release
    editor = docker.panel.map_widget.editor
    u0, v0 = editor.lights.lights[0].u, editor.lights.lights[0].v
    editor.press(u0, v0)
    for k in range(1, 11):
        editor.drag(u0 + 0.004 * k, v0 - 0.006 * k)
        wait(0.05)
    editor.release()
    deadline = time.monotonic() + 60
    while (docker.controller.busy or docker.controller.renders < 2) and time.monotonic() < deadline:
        wait(0.2)
    say(f"dragged: {docker.controller.previews} previews, {docker.controller.renders} renders")
    wait(2.0)
    out = Path(os.environ["SSN_FIGURE_OUT"])
    QApplication.primaryScreen().grabWindow(0).save(str(out))
    docker.panel.scroll.ensureWidgetVisible(docker.panel.from_guide)  # the Camera group, scrolled into view
    wait(1.0)
    QApplication.primaryScreen().grabWindow(0).save(str(out.with_name(out.stem + "-camera" + out.suffix)))
    say("grabbed")
    docker.controller.engine.shutdown()
    QApplication.quit()


def main(argv: list[str] | None = None) -> int:
    import argparse
    import random
    import shutil
    import subprocess
    import tempfile

    import numpy as np

    from plugin_krita.install import install
    from ssn_engine.samples import pawn_cutout, studio_background

    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    p.add_argument("--out", default="docs/img/krita-window.png")
    args = p.parse_args(argv)
    out = Path(args.out).resolve()
    repo = Path(__file__).resolve().parents[1]
    kritarunner, xvfb = shutil.which("kritarunner"), shutil.which("xvfb-run")
    if kritarunner is None or xvfb is None:
        raise SystemExit("needs kritarunner and xvfb-run: apt-get install krita xvfb")
    with tempfile.TemporaryDirectory() as tmp:
        work = Path(tmp)
        pawn = pawn_cutout()
        background = np.dstack([studio_background(), np.full((H, W), 255, np.uint8)])
        for name, rgba in (("pawn", pawn), ("background", background)):
            (work / f"{name}.bgra").write_bytes(np.ascontiguousarray(rgba[..., [2, 1, 0, 3]]).tobytes())
        pykrita = install(work / "pykrita", python=sys.executable).parent
        env = {k: v for k, v in os.environ.items() if k not in ("QT_QPA_PLATFORM", "SSN_SHADOW_ENGINE_CONFIG")}
        config = work / "config"  # a fresh Krita profile that paints its canvas without OpenGL (Xvfb has none)
        config.mkdir()
        (config / "kritadisplayrc").write_text("[General]\nOpenGLRenderer=none\n")
        env.update(
            XDG_CONFIG_HOME=str(config),
            SSN_FIGURE_OUT=str(out),
            SSN_FIGURE_WORK=str(work),
            PYTHONPATH=os.pathsep.join([str(pykrita), str(Path(__file__).parent), str(repo)]),
            PATH=os.pathsep.join(["/usr/bin", "/bin", env.get("PATH", "")]),  # Krita's own python3 first
        )
        command = [xvfb, "-a", "-n", str(random.randint(200, 900)), "-s", "-screen 0 1366x768x24"]
        command += [kritarunner, "-s", Path(__file__).stem, "-f", "inside"]
        log = work / "krita.log"
        with open(log, "w") as sink:
            try:
                subprocess.run(command, env=env, stdout=sink, stderr=subprocess.STDOUT, timeout=180)
            except subprocess.TimeoutExpired:
                pass  # kritarunner may not exit after the script: the picture counts
        said = log.read_text(errors="replace")
        said = "\n".join(ln for ln in said.splitlines() if "figure:" in ln or "rror" in ln)[-3000:]
    if not out.exists():
        raise SystemExit(f"Krita wrote no picture:\n{said}")
    print(f"wrote {out}", file=sys.stderr)
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
