"""The "Soft Shadow" docker inside Krita (thin: builds the engine client, host adapter and panel)."""

from __future__ import annotations

from krita import DockWidget, Krita
from PyQt5.QtWidgets import QApplication, QFrame, QScrollArea

from .adapters.host import KritaHost
from .controller import ShadowController
from .engine import EngineProcess
from .ui.panel import ShadowPanel

DOCKER_ID = "ssn_shadow_docker"
TITLE = "Soft Shadow"


class SoftShadowDocker(DockWidget):
    """Krita's dock widget around the ShadowPanel."""

    def __init__(self) -> None:
        super().__init__()
        self.setWindowTitle(TITLE)
        self.engine = EngineProcess(parent=self)
        self.controller = ShadowController(self.engine, KritaHost(Krita.instance()), self)
        self.panel = ShadowPanel(self.controller)
        # Docked in a short window, the panel scrolls instead of squeezing its controls over each other.
        scroll = QScrollArea()
        scroll.setWidgetResizable(True)
        scroll.setFrameShape(QFrame.NoFrame)
        scroll.setWidget(self.panel)
        self.setWidget(scroll)
        app = QApplication.instance()
        if app is not None:
            app.aboutToQuit.connect(self.engine.shutdown)

    def canvasChanged(self, canvas) -> None:  # noqa: N802 (Krita's API)
        """Another document or view: the next Generate reads its source afresh, with that document's camera."""
        try:
            self.controller.forget_cutout()
            self.panel.document_changed(Krita.instance().activeDocument())
        except Exception as exc:  # never crash the host
            self.panel.show_message("error", f"Soft Shadow: {exc}")
