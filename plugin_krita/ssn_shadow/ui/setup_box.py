"""The docker's Set up box: shown while a packaged plug-in has no engine (or an older one), it runs the host kit's
:class:`~ssn_engine.host_kit.engine_setup.SetupJob` off the UI thread and shows its progress, a Cancel, and the log.

Thin: what is missing, what to say and how to set up are the kit's (:mod:`engine_setup`); this only shows them.
"""

from __future__ import annotations

from pathlib import Path

from PyQt5.QtCore import QTimer, QUrl, pyqtSignal
from PyQt5.QtGui import QDesktopServices
from PyQt5.QtWidgets import QHBoxLayout, QLabel, QProgressBar, QPushButton, QVBoxLayout, QWidget

from ..shared import engine_config, engine_setup

POLL_MS = 100


class SetupBox(QWidget):
    """What the engine lacks, Set up (or Update), a progress bar, Cancel and Open log."""

    finished = pyqtSignal(bool)  # True: the engine is set up (the panel works now)

    def __init__(self, plugin_dir: Path, parent: QWidget | None = None) -> None:
        super().__init__(parent)
        self.plugin_dir = Path(plugin_dir)
        self.job: engine_setup.SetupJob | None = None
        self.bundle: engine_setup.Bundle | None = None
        layout = QVBoxLayout(self)
        layout.setContentsMargins(6, 6, 6, 6)
        self.message = QLabel()
        self.message.setWordWrap(True)
        self.progress = QProgressBar()
        self.progress.setRange(0, 100)
        self.setup_button = QPushButton("Set up")
        self.cancel_button = QPushButton("Cancel")
        self.log_button = QPushButton("Open log")
        buttons = QHBoxLayout()
        for button in (self.setup_button, self.cancel_button, self.log_button):
            buttons.addWidget(button)
        layout.addWidget(self.message)
        layout.addWidget(self.progress)
        layout.addLayout(buttons)
        self.setup_button.clicked.connect(self.start)
        self.cancel_button.clicked.connect(self.cancel)
        self.log_button.clicked.connect(self.open_log)
        self._timer = QTimer(self)
        self._timer.setInterval(POLL_MS)
        self._timer.timeout.connect(self._poll)
        self.refresh()

    @property
    def log_path(self) -> Path:
        return engine_setup.data_dir() / "setup.log"

    def refresh(self) -> bool:
        """Show the box if the engine needs setting up (hide it otherwise); returns whether it shows."""
        if self.job is not None and self.job.running:
            return True
        try:
            engine_config.load_engine_config(self.plugin_dir, "krita")
        except engine_config.EngineSetupNeeded as needed:
            self.bundle = needed.bundle
            self._show_idle(str(needed), "Update" if needed.state.status == "outdated" else "Set up")
            return True
        except engine_config.EngineConfigError:
            pass  # not a packaged plug-in's problem: the panel says it on the first request
        self.setVisible(False)
        return False

    def _show_idle(self, text: str, action: str, error: bool = False) -> None:
        self.message.setText(text)
        self.message.setStyleSheet("color: #c0392b;" if error else "")
        self.setup_button.setText(action)
        self.setup_button.setEnabled(True)
        self.cancel_button.setVisible(False)
        self.progress.setVisible(False)
        self.log_button.setVisible(self.log_path.exists())
        self.setVisible(True)

    def start(self) -> None:
        """Set up (or update, or resume) on a thread of its own."""
        if self.bundle is None or (self.job is not None and self.job.running):
            return
        setup = engine_setup.EngineSetup(self.bundle, engine_setup.data_dir())
        self.job = engine_setup.SetupJob(setup).start()
        self.message.setStyleSheet("")
        self.setup_button.setEnabled(False)
        self.cancel_button.setVisible(True)
        self.cancel_button.setEnabled(True)
        self.progress.setVisible(True)
        self.progress.setValue(0)
        self.log_button.setVisible(True)
        self._timer.start()

    def cancel(self) -> None:
        if self.job is not None:
            self.job.cancel()
            self.cancel_button.setEnabled(False)
            self.message.setText("Cancelling...")

    def open_log(self) -> None:
        QDesktopServices.openUrl(QUrl.fromLocalFile(str(self.log_path)))

    def _poll(self) -> None:
        if self.job is None:
            return
        for event in self.job.events():
            self.progress.setValue(round(100 * event.fraction))
            self.message.setText(event.text)
            if event.done:
                self._timer.stop()
                if event.error:
                    self._show_idle(event.error, "Resume" if event.cancelled else "Try again", not event.cancelled)
                    self.finished.emit(False)
                else:
                    self.setVisible(False)
                    self.finished.emit(True)
