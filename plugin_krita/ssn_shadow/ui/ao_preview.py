"""The AO preview: the cutout's ambient-occlusion map with the framed mask, and a brush on it.

Coordinates handed out are fractions of the engine's N x N frame (x right,
y down), as the protocol's AO edits expect.
"""

from __future__ import annotations

import math

from PyQt5.QtCore import QPointF, QRectF, QSize, Qt, pyqtSignal
from PyQt5.QtGui import QColor, QImage, QPainter, QPen
from PyQt5.QtWidgets import QSizePolicy, QWidget


def mask_overlay(mask: bytes, n: int) -> QImage:
    """A translucent blue image where the mask is set (ARGB32 premultiplied)."""
    data = bytearray(4 * n * n)
    for i, m in enumerate(mask):
        if m:
            a = m * 90 // 255
            data[4 * i : 4 * i + 4] = bytes((a, a * 40 // 255, a * 20 // 255, a))  # B, G, R, A premultiplied
    return QImage(bytes(data), n, n, 4 * n, QImage.Format_ARGB32_Premultiplied).copy()


class AOPreview(QWidget):
    """Shows the AO map; a left-button drag paints brush dabs."""

    brushed = pyqtSignal(float, float, bool)  # x, y (frame fractions), stroke_started

    def __init__(self, parent: QWidget | None = None) -> None:
        super().__init__(parent)
        self._ao: QImage | None = None
        self._mask: QImage | None = None
        self.brush_radius = 0.05
        self._last: tuple[float, float] | None = None
        self._cursor: QPointF | None = None
        self.setMinimumSize(120, 120)
        self.setMouseTracking(True)
        policy = QSizePolicy(QSizePolicy.Expanding, QSizePolicy.Preferred)
        policy.setHeightForWidth(True)
        self.setSizePolicy(policy)
        self.setToolTip("Ambient occlusion of the cutout. Paint on it to darken or lighten the contact shadow.")

    def sizeHint(self) -> QSize:
        return QSize(200, 200)

    def hasHeightForWidth(self) -> bool:
        return True

    def heightForWidth(self, width: int) -> int:
        return min(width, 260)

    @property
    def has_image(self) -> bool:
        return self._ao is not None

    def set_images(self, ao: bytes, mask: bytes, n: int) -> None:
        self._ao = QImage(ao, n, n, n, QImage.Format_Grayscale8).copy()
        self._mask = mask_overlay(mask, n)
        self.update()

    def clear(self) -> None:
        self._ao = self._mask = None
        self.update()

    def frame_rect(self) -> QRectF:
        s = min(self.width(), self.height())
        return QRectF((self.width() - s) / 2, (self.height() - s) / 2, s, s)

    def to_frame(self, pos: QPointF) -> tuple[float, float]:
        r = self.frame_rect()
        return (pos.x() - r.left()) / r.width(), (pos.y() - r.top()) / r.height()

    def _dab(self, pos: QPointF, started: bool) -> None:
        x, y = self.to_frame(pos)
        if not (0.0 <= x <= 1.0 and 0.0 <= y <= 1.0):
            return
        if not started and self._last is not None:
            if math.hypot(x - self._last[0], y - self._last[1]) < self.brush_radius / 3:
                return  # spacing: a dab every third of a radius
        self._last = (x, y)
        self.brushed.emit(x, y, started)

    def mousePressEvent(self, event) -> None:
        if event.button() == Qt.LeftButton and self.has_image:
            self._last = None
            self._dab(QPointF(event.pos()), True)

    def mouseMoveEvent(self, event) -> None:
        self._cursor = QPointF(event.pos())
        if event.buttons() & Qt.LeftButton and self.has_image:
            self._dab(QPointF(event.pos()), False)
        self.update()

    def leaveEvent(self, event) -> None:
        self._cursor = None
        self.update()

    def paintEvent(self, event) -> None:
        p = QPainter(self)
        p.setRenderHint(QPainter.Antialiasing)
        r = self.frame_rect()
        if self._ao is None:
            p.fillRect(r, QColor(60, 60, 60))
            p.setPen(QColor(200, 200, 200))
            p.drawText(r, Qt.AlignCenter | Qt.TextWordWrap, "Generate a shadow to see\nits ambient occlusion")
        else:
            p.drawImage(r, self._ao)
            if self._mask is not None:
                p.drawImage(r, self._mask)
            if self._cursor is not None:
                p.setPen(QPen(QColor(255, 120, 0), 1))
                p.setBrush(Qt.NoBrush)
                rad = self.brush_radius * r.width()
                p.drawEllipse(self._cursor, rad, rad)
        p.end()
