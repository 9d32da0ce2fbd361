"""The live preview of a light drag: the image as a thumbnail with the shadow the engine multiplied on."""

from __future__ import annotations

from PyQt5.QtCore import QRectF, QSize
from PyQt5.QtGui import QImage, QPainter
from PyQt5.QtWidgets import QSizePolicy, QWidget

MAX_HEIGHT = 220  # pixels of the docker it may take


class DragPreview(QWidget):
    """Shows the latest preview image, scaled to the widget's width; hidden until there is one."""

    def __init__(self, parent: QWidget | None = None) -> None:
        super().__init__(parent)
        self.image: QImage | None = None
        policy = QSizePolicy(QSizePolicy.Expanding, QSizePolicy.Preferred)
        policy.setHeightForWidth(True)
        self.setSizePolicy(policy)
        self.setToolTip("While a light is dragged: the image with the new shadow (the layer follows on release)")
        self.setVisible(False)

    def set_image(self, rgb: bytes, width: int, height: int) -> None:
        """Show packed 8-bit RGB pixels (width x height)."""
        self.image = QImage(rgb, width, height, 3 * width, QImage.Format.Format_RGB888).copy()
        if not self.isVisible():
            self.setVisible(True)
            self.updateGeometry()
        self.update()

    def sizeHint(self) -> QSize:
        return QSize(320, self.heightForWidth(320))

    def hasHeightForWidth(self) -> bool:
        return True

    def heightForWidth(self, width: int) -> int:
        if self.image is None or self.image.width() == 0:
            return width * 3 // 4
        return min(MAX_HEIGHT, round(width * self.image.height() / self.image.width()))

    def paintEvent(self, event) -> None:
        if self.image is None:
            return
        scale = min(self.width() / self.image.width(), self.height() / self.image.height())
        w, h = self.image.width() * scale, self.image.height() * scale
        painter = QPainter(self)
        painter.setRenderHint(QPainter.RenderHint.SmoothPixmapTransform)
        painter.drawImage(QRectF((self.width() - w) / 2, (self.height() - h) / 2, w, h), self.image)
        painter.end()
