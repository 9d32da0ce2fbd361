"""Qt offscreen for the plug-in's logic and UI tests."""

import os

os.environ.setdefault("QT_QPA_PLATFORM", "offscreen")

import pytest  # noqa: E402


@pytest.fixture(scope="session")
def qapp(tmp_path_factory):
    from PyQt5.QtCore import QSettings
    from PyQt5.QtWidgets import QApplication

    # the panel remembers its folded sections in Qt's settings: the tests' own, not the user's
    QSettings.setPath(QSettings.Format.NativeFormat, QSettings.Scope.UserScope, str(tmp_path_factory.mktemp("qt")))
    return QApplication.instance() or QApplication([])
