"""The AO preview: the cutout's ambient-occlusion map with the framed mask, and a brush on it.

It shows the part of the frame around the cutout (zoomed in, not the whole
frame), with the occlusion's contrast stretched so that the contact shadow
is plainly visible, and occlusion fainter than :data:`NOISE_FLOOR` of the
darkest shown white: the network's faint occlusion far from the object
(which the stretch would turn into grey swirls over the whole frame) casts
no visible shadow. Coordinates handed out are fractions of the engine's
N x N frame (x right, y down), as the protocol's AO edits expect.
"""

from __future__ import annotations

import math

from PyQt5.QtCore import QPointF, QRectF, QSize, Qt, pyqtSignal
from PyQt5.QtGui import QColor, QImage, QPainter, QPen
from PyQt5.QtWidgets import QSizePolicy, QWidget


VIEW_MARGIN = 0.35  # share of the cutout's larger side shown around it
MAX_STRETCH = 4.0  # the occlusion is darkened at most this many times
NOISE_FLOOR = 0.12  # occlusion below this share of the darkest is shown white (it ramps in up to twice that)


def contrast_table(ao: bytes) -> bytes:
    """A byte translation table that stretches the occlusion (255 - AO) so its darkest value shows nearly black,
    and shows occlusion fainter than :data:`NOISE_FLOOR` of the darkest as none."""
    occlusion = 255 - min(ao) if ao else 0
    k = min(MAX_STRETCH, 230 / max(occlusion, 1))
    floor = NOISE_FLOOR * occlusion

    def shown(v: int) -> int:
        o = 255 - v
        ramp = min(1.0, max(0.0, (o - floor) / max(floor, 1e-6)))  # 0 below the floor, 1 from twice it
        return max(0, 255 - round(o * k * ramp))

    return bytes(shown(v) for v in range(256))


def view_of(mask: bytes, n: int) -> tuple[float, float, float]:
    """The square of the frame to show (left, top, size as frame fractions): the cutout and the ground around
    its base; the whole frame when the mask is empty."""
    rows = [y for y in range(n) if any(mask[y * n : (y + 1) * n])]
    if not rows:
        return 0.0, 0.0, 1.0
    cols = [x for x in range(n) if any(mask[x::n])]
    x0, x1, y0, y1 = cols[0] / n, (cols[-1] + 1) / n, rows[0] / n, (rows[-1] + 1) / n
    size = min(1.0, max(x1 - x0, y1 - y0) * (1 + 2 * VIEW_MARGIN))
    left = min(max(0.5 * (x0 + x1) - 0.5 * size, 0.0), 1.0 - size)
    top = min(max(y1 + VIEW_MARGIN * (y1 - y0) - size, 0.0), 1.0 - size)  # the base near the bottom edge
    return left, top, size


def mask_overlay(mask: bytes, n: int) -> QImage:
    """A translucent blue image where the mask is set (ARGB32 premultiplied)."""
    alpha = bytes(m * 90 // 255 for m in range(256))
    data = bytearray(4 * n * n)
    data[0::4] = mask.translate(alpha)  # B, G, R, A premultiplied, by byte tables (no loop over pixels)
    data[1::4] = mask.translate(bytes(a * 40 // 255 for a in alpha))
    data[2::4] = mask.translate(bytes(a * 20 // 255 for a in alpha))
    data[3::4] = mask.translate(alpha)
    return QImage(bytes(data), n, n, 4 * n, QImage.Format_ARGB32_Premultiplied).copy()


class AOPreview(QWidget):
    """Shows the AO map; a left-button drag paints brush dabs."""

    brushed = pyqtSignal(float, float, bool)  # x, y (frame fractions), stroke_started

    def __init__(self, parent: QWidget | None = None) -> None:
        super().__init__(parent)
        self._ao: QImage | None = None
        self._mask: QImage | None = None
        self.view = (0.0, 0.0, 1.0)  # left, top, size of the shown square, frame fractions
        self._n = 1
        self._mask_bytes = b""
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
        shown = bytes(ao).translate(contrast_table(ao))
        self._ao = QImage(shown, n, n, n, QImage.Format_Grayscale8).copy()
        self._mask = mask_overlay(mask, n)
        if mask != self._mask_bytes:  # a new cutout: frame it (AO edits keep the view while the user paints)
            self.view, self._mask_bytes = view_of(mask, n), bytes(mask)
        self._n = n
        self.update()

    def clear(self) -> None:
        self._ao = self._mask = None
        self.view, self._mask_bytes = (0.0, 0.0, 1.0), b""
        self.update()

    def frame_rect(self) -> QRectF:
        s = min(self.width(), self.height())
        return QRectF((self.width() - s) / 2, (self.height() - s) / 2, s, s)

    def to_frame(self, pos: QPointF) -> tuple[float, float]:
        r = self.frame_rect()
        left, top, size = self.view
        return left + size * (pos.x() - r.left()) / r.width(), top + size * (pos.y() - r.top()) / r.height()

    def _source(self) -> QRectF:
        left, top, size = self.view
        return QRectF(left * self._n, top * self._n, size * self._n, size * self._n)

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
        if event.button() == Qt.MouseButton.LeftButton and self.has_image:
            self._last = None
            self._dab(QPointF(event.pos()), True)

    def mouseMoveEvent(self, event) -> None:
        self._cursor = QPointF(event.pos())
        if event.buttons() & Qt.MouseButton.LeftButton and self.has_image:
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
            p.drawText(
                r,
                Qt.AlignmentFlag.AlignCenter | Qt.TextFlag.TextWordWrap,
                "Generate a shadow to see\nits ambient occlusion",
            )
        else:
            p.drawImage(r, self._ao, self._source())
            if self._mask is not None:
                p.drawImage(r, self._mask, self._source())
            if self._cursor is not None:
                p.setPen(QPen(QColor(255, 120, 0), 1))
                p.setBrush(Qt.BrushStyle.NoBrush)
                rad = self.brush_radius * r.width() / self.view[2]
                p.drawEllipse(self._cursor, rad, rad)
        p.end()
