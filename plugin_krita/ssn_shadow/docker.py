"""The "Soft Shadow" docker inside Krita (thin: builds the engine client, host adapter, models and panel)."""

from __future__ import annotations

from krita import DockWidget, Krita
from PyQt5.QtWidgets import QApplication, QVBoxLayout

from .adapters.host import KritaHost
from .controller import ShadowController
from .engine import PLUGIN_DIR, EngineProcess
from .persistence import DocumentModels
from .ui.panel import ShadowPanel
from .ui.setup_box import SetupBox

DOCKER_ID = "ssn_shadow_docker"
TITLE = "Soft Shadow"


class SoftShadowDocker(DockWidget):
    """Krita's dock widget around the ShadowPanel."""

    def __init__(self) -> None:
        super().__init__()
        self.setWindowTitle(TITLE)
        self.engine = EngineProcess(parent=self)
        host = KritaHost(Krita.instance())
        self.models = DocumentModels(host)
        self.controller = ShadowController(self.engine, host, self.models.model_for(host.active_document()), self)
        self.panel = ShadowPanel(self.controller)  # its controls scroll in a short dock, Generate stays in view
        self.setup_box = SetupBox(PLUGIN_DIR)  # a packaged plug-in's Set up, shown while its engine is missing
        self.setup_box.finished.connect(self._set_up)
        layout = self.panel.layout()
        assert isinstance(layout, QVBoxLayout)
        layout.insertWidget(0, self.setup_box)  # above the controls, hidden once set up
        self.setWidget(self.panel)
        self.controller.watch_history()
        host.watch_closing(self._document_closed)
        app = QApplication.instance()
        if app is not None:
            app.aboutToQuit.connect(self.engine.shutdown)

    def _set_up(self, ready: bool) -> None:
        if ready:
            self.engine.stop()  # the next request starts the engine just set up
            self.controller.model.report_status("info", "The shadow engine is set up: press Generate.")

    def canvasChanged(self, canvas) -> None:  # noqa: N802 (Krita's API)
        """Another document or view: the docker shows that document's settings, and the next Generate reads its
        source afresh."""
        try:
            self.controller.forget_cutout()
            self.controller.watch_history()  # a new window has its own undo action
            self._show_active_document()
        except Exception as exc:  # never crash the host
            self.panel.show_message("error", f"Soft Shadow: {exc}")

    def _document_closed(self) -> None:
        """A view or document was closed: where the docker showed that document's state (its message, say),
        it shows the active document's, or a new image's where none is open."""
        try:
            if self.models.is_closed(self.controller.model):
                self.controller.forget_cutout()
                self._show_active_document()
        except Exception as exc:  # never crash the host
            self.panel.show_message("error", f"Soft Shadow: {exc}")

    def _show_active_document(self) -> None:
        self.controller.set_model(self.models.model_for(self.controller.host.open_active_document()))
        self.panel.show_model(self.controller.model)
