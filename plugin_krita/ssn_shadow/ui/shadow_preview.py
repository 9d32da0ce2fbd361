"""The docker's preview: the image as a thumbnail with its shadow and the horizon, following a dragged light.

The engine draws the thumbnail (the image without its shadow layer, the
shadow multiplied on, the horizon as a line: dashed where the image's own
horizon is given, dotted where the model read it from the outline). The
preview keeps its place in the docker from the start, whether or not it has
an image yet, so that its first image never moves the light map under the
mouse in the middle of a drag.
"""

from __future__ import annotations

from PyQt5.QtCore import QRectF, QSize, Qt, pyqtSignal
from PyQt5.QtGui import QColor, QImage, QPainter
from PyQt5.QtWidgets import QSizePolicy, QWidget

__all__ = ["MAX_HEIGHT", "ShadowPreview"]

MAX_HEIGHT = 200  # pixels of the docker it takes at most
PLACEHOLDER = "After Generate: the image with its shadow and the horizon; it follows a dragged light"


class ShadowPreview(QWidget):
    """Shows the latest preview image, scaled into a box of a fixed shape (its height depends only on the
    width)."""

    resized = pyqtSignal(int, int)  # the box's width and height in device pixels: previews drawn as large as that

    def __init__(self, parent: QWidget | None = None) -> None:
        super().__init__(parent)
        self.image: QImage | None = None
        policy = QSizePolicy(QSizePolicy.Expanding, QSizePolicy.Fixed)
        policy.setHeightForWidth(True)
        self.setSizePolicy(policy)
        self.setMinimumSize(120, self.heightForWidth(120))
        self.setToolTip(
            "The image with its shadow and horizon (dashed: the horizon you gave; dotted: the one read from the "
            "cutout's outline). While a light is dragged it follows the light; the layer follows on release."
        )

    def set_image(self, rgb: bytes, width: int, height: int) -> None:
        """Show packed 8-bit RGB pixels (width x height)."""
        self.image = QImage(rgb, width, height, 3 * width, QImage.Format.Format_RGB888).copy()
        self.update()

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
            scale = min(self.width() / self.image.width(), self.height() / self.image.height())
            w, h = self.image.width() * scale, self.image.height() * scale
            painter.setRenderHint(QPainter.RenderHint.SmoothPixmapTransform)
            painter.drawImage(QRectF((self.width() - w) / 2, (self.height() - h) / 2, w, h), self.image)
        painter.end()
