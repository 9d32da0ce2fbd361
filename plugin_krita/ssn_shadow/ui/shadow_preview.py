"""The docker's preview: the image as a thumbnail with its shadow and the horizon, following a dragged light.

The engine draws the thumbnail (the image without its shadow layer, the
shadow multiplied on, the horizon as a line: dashed where the image's own
horizon is given, dotted where the model read it from the outline). The
preview keeps its place in the docker from the start, whether or not it has
an image yet, so that its first image never moves the light map under the
mouse in the middle of a drag.

Below the analysed cutout it draws the lift handle: a bar at the ground beneath the object (its lowest point
plus the lift), which a vertical drag moves (:attr:`ShadowPreview.liftDragged`, canvas rows: the preview's rows
over its scale).
"""

from __future__ import annotations

from PyQt5.QtCore import QPointF, QRectF, QSize, Qt, pyqtSignal
from PyQt5.QtGui import QColor, QImage, QPainter, QPen
from PyQt5.QtWidgets import QSizePolicy, QWidget

__all__ = ["MAX_HEIGHT", "ShadowPreview", "lift_at", "handle_row"]

MAX_HEIGHT = 200  # pixels of the docker it takes at most
PLACEHOLDER = "After Generate: the image with its shadow and the horizon; it follows a dragged light"
GRAB = 8  # pixels: a press this close to the lift handle drags it
HANDLE = 9  # pixels: half the handle's width


def handle_row(lift_row: int, lift: float) -> float:
    """The canvas row (an edge between rows) of the ground beneath a cutout whose lift counts from canvas row
    ``lift_row`` (its lowest pixel's), lifted ``lift`` rows."""
    return lift_row + 1 + lift


def lift_at(y: float, top: float, rows_per_pixel: float, lift_row: int) -> float:
    """The lift (whole canvas rows, at least 0) whose ground lies at the preview's pixel row ``y``, the canvas drawn
    from ``top`` at ``rows_per_pixel`` canvas rows a pixel (the preview's scale's inverse), counted from canvas row
    ``lift_row``."""
    return float(max(0, round((y - top) * rows_per_pixel - (lift_row + 1))))


class ShadowPreview(QWidget):
    """Shows the latest preview image, scaled into a box of a fixed shape (its height depends only on the
    width)."""

    resized = pyqtSignal(int, int)  # the box's width and height in device pixels: previews drawn as large as that
    liftDragged = pyqtSignal(float, bool)  # the lift handle dragged to a lift (canvas rows); True: released there

    def __init__(self, parent: QWidget | None = None) -> None:
        super().__init__(parent)
        self.image: QImage | None = None
        # the cutout's bbox, canvas size and the row its lift counts from
        self.ground: tuple[tuple[int, int, int, int], tuple[int, int], int] | None = None
        self.lift = 0.0
        self._dragging = False
        self.setMouseTracking(True)
        policy = QSizePolicy(QSizePolicy.Expanding, QSizePolicy.Fixed)
        policy.setHeightForWidth(True)
        self.setSizePolicy(policy)
        self.setMinimumSize(120, self.heightForWidth(120))
        self.setToolTip(
            "The image with its shadow and horizon (dashed: the horizon you gave; dotted: the one read from the "
            "cutout's outline). While a light is dragged it follows the light; the layer follows on release. Drag the "
            "bar under the object to lift it off the ground."
        )

    def set_image(self, rgb: bytes, width: int, height: int) -> None:
        """Show packed 8-bit RGB pixels (width x height)."""
        self.image = QImage(rgb, width, height, 3 * width, QImage.Format.Format_RGB888).copy()
        self.update()

    def set_ground(self, ground: tuple[tuple[int, int, int, int], tuple[int, int], int] | None, lift: float) -> None:
        """The analysed cutout's bbox, canvas size and lift row (None: no handle), and its lift in canvas rows."""
        if not self._dragging:  # the drag's own position, not the model's echo of it
            self.ground, self.lift = ground, float(lift)
        self.update()

    def image_rect(self) -> QRectF | None:
        """Where the image is drawn in the widget (None: no image)."""
        if self.image is None or self.image.width() == 0 or self.image.height() == 0:
            return None
        scale = min(self.width() / self.image.width(), self.height() / self.image.height())
        w, h = self.image.width() * scale, self.image.height() * scale
        return QRectF((self.width() - w) / 2, (self.height() - h) / 2, w, h)

    def handle_pos(self) -> QPointF | None:
        """The lift handle's centre in the widget (None: no image or no cutout)."""
        rect, ground = self.image_rect(), self.ground
        if rect is None or ground is None:
            return None
        bbox, (width, height), row = ground
        return QPointF(
            rect.left() + (bbox[0] + bbox[2]) / 2 * rect.width() / width,
            rect.top() + handle_row(row, self.lift) * rect.height() / height,
        )

    def _lift_at(self, y: float) -> float:
        rect, ground = self.image_rect(), self.ground
        assert rect is not None and ground is not None, "a drag has a handle"
        return lift_at(y, rect.top(), ground[1][1] / rect.height(), ground[2])

    def mousePressEvent(self, event) -> None:  # noqa: N802 (Qt's API)
        pos = self.handle_pos()
        if event.button() == Qt.MouseButton.LeftButton and pos is not None and self._near(event.pos(), pos):
            self._dragging = True
            event.accept()
            return
        super().mousePressEvent(event)

    def mouseMoveEvent(self, event) -> None:  # noqa: N802 (Qt's API)
        if self._dragging:
            self.lift = self._lift_at(event.pos().y())
            self.update()
            self.liftDragged.emit(self.lift, False)
            return
        pos = self.handle_pos()
        near = pos is not None and self._near(event.pos(), pos)
        self.setCursor(Qt.CursorShape.SizeVerCursor if near else Qt.CursorShape.ArrowCursor)

    def mouseReleaseEvent(self, event) -> None:  # noqa: N802 (Qt's API)
        if self._dragging and event.button() == Qt.MouseButton.LeftButton:
            self._dragging = False
            self.lift = self._lift_at(event.pos().y())
            self.update()
            self.liftDragged.emit(self.lift, True)
            return
        super().mouseReleaseEvent(event)

    @staticmethod
    def _near(point, handle: QPointF) -> bool:
        return abs(point.x() - handle.x()) <= HANDLE + GRAB and abs(point.y() - handle.y()) <= GRAB

    def clear(self) -> None:
        """No image (another document): the placeholder again, in the same place."""
        self.image = None
        self.update()

    def resizeEvent(self, event) -> None:
        super().resizeEvent(event)
        ratio = self.devicePixelRatioF()
        self.resized.emit(round(self.width() * ratio), round(self.height() * ratio))

    def sizeHint(self) -> QSize:
        return QSize(320, self.heightForWidth(320))

    def minimumSizeHint(self) -> QSize:
        return QSize(120, self.heightForWidth(120))

    def hasHeightForWidth(self) -> bool:
        return True

    def heightForWidth(self, width: int) -> int:
        return min(MAX_HEIGHT, width * 5 // 8)

    def paintEvent(self, event) -> None:
        painter = QPainter(self)
        if self.image is None or self.image.width() == 0 or self.image.height() == 0:
            painter.fillRect(self.rect(), QColor(60, 60, 60))
            painter.setPen(QColor(200, 200, 200))
            painter.drawText(
                QRectF(self.rect()).adjusted(8, 4, -8, -4),
                Qt.AlignmentFlag.AlignCenter | Qt.TextFlag.TextWordWrap,
                PLACEHOLDER,
            )
        else:
            rect = self.image_rect()
            assert rect is not None, "an image is drawn somewhere"
            painter.setRenderHint(QPainter.RenderHint.SmoothPixmapTransform)
            painter.drawImage(rect, self.image)
            self._paint_handle(painter)
        painter.end()

    def _paint_handle(self, painter: QPainter) -> None:
        """The lift handle: a bar at the ground beneath the object, a dashed line up to its lowest point."""
        pos, ground, rect = self.handle_pos(), self.ground, self.image_rect()
        if pos is None or ground is None or rect is None:
            return
        foot = rect.top() + ground[0][3] * rect.height() / ground[1][1]
        painter.setRenderHint(QPainter.RenderHint.Antialiasing)
        if pos.y() - foot >= 1:
            painter.setPen(QPen(QColor(255, 255, 255), 1, Qt.PenStyle.DashLine))
            painter.drawLine(QPointF(pos.x(), foot), pos)
        for colour, width in ((QColor(0, 0, 0), 4), (QColor(255, 200, 60), 2)):
            painter.setPen(QPen(colour, width))
            painter.drawLine(QPointF(pos.x() - HANDLE, pos.y()), QPointF(pos.x() + HANDLE, pos.y()))
