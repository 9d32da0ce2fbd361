"""The light map editor widget: the upper hemisphere drawn 2:1, the camera's forward direction in the middle.

Click to add a light, drag to move it, wheel for its size (Shift: intensity),
right-click or Delete to remove. The gestures are the host kit's
``LightMapEditor`` (the same as GIMP's); this widget draws the map and turns
Qt's mouse events into the editor's calls.

While a light moves (a drag, a slider) the map's picture is made again at most
every ``PICTURE_INTERVAL_MS`` (the markers follow every move): the picture is
pure Python, several milliseconds for a large disk light, on Krita's UI
thread, and at the mouse's rate it took CPU from the worker rendering the
drag's previews. The edit that ends the move draws it at once.
"""

from __future__ import annotations

from PyQt5.QtCore import QElapsedTimer, QPointF, QRectF, QSize, Qt, QTimer, pyqtSignal
from PyQt5.QtGui import QColor, QImage, QPainter, QPen, QPolygonF
from PyQt5.QtWidgets import QSizePolicy, QWidget

from ..shared import light_editor
from ..shared import light_map as lm
from ..shared import light_map_picture
from .folding import MAP_MIN_HEIGHT

PICTURE_INTERVAL_MS = 50  # while a light moves, the map's picture is made at most this often


class LightMapWidget(QWidget):
    """Shows one ``LightMapEditor`` and forwards mouse and key events to it."""

    lightsChanged = pyqtSignal(bool, bool)  # live (a drag or slider move), new_stroke (a new undo step)
    selectionChanged = pyqtSignal(int)  # index of the selected light, -1 for none

    def __init__(self, light_map: lm.LightMap | None = None, parent: QWidget | None = None) -> None:
        super().__init__(parent)
        self.editor = light_editor.LightMapEditor(light_map, self._changed, self._selected)
        self._picture: QImage | None = None
        self._made = QElapsedTimer()  # since the picture was made
        self._catch_up = QTimer(self)  # draws the picture of the lights a throttled move left behind
        self._catch_up.setSingleShot(True)
        self._catch_up.timeout.connect(self._redraw)
        self.setFocusPolicy(Qt.FocusPolicy.ClickFocus)
        self.setMouseTracking(False)
        self.setMinimumSize(160, MAP_MIN_HEIGHT)  # a short dock caps its height (the panel: setMaximumHeight)
        policy = QSizePolicy(QSizePolicy.Expanding, QSizePolicy.Preferred)
        policy.setHeightForWidth(True)
        self.setSizePolicy(policy)
        self.setToolTip(
            "Click: add a light · drag: move · wheel: size · Shift+wheel: intensity · right-click or Del: remove"
        )

    @property
    def light_map(self) -> lm.LightMap:
        return self.editor.lights

    @property
    def selected(self) -> int | None:
        return self.editor.selected

    # -- geometry ------------------------------------------------------------------
    def sizeHint(self) -> QSize:
        return QSize(320, 160)

    def hasHeightForWidth(self) -> bool:
        return True

    def heightForWidth(self, width: int) -> int:
        """2:1, at least 80 px, within the widget's maximum height (a short dock's cap: the map is drawn 2:1
        within its box, narrower than the box)."""
        return max(self.minimumHeight(), min(max(80, width // 2), self.maximumHeight()))

    def map_rect(self) -> QRectF:
        w, h = self.width(), self.height()
        mw = min(w, 2 * h)
        return QRectF((w - mw) / 2, (h - mw / 2) / 2, mw, mw / 2)

    def to_uv(self, pos: QPointF) -> tuple[float, float]:
        r = self.map_rect()
        return (pos.x() - r.left()) / r.width(), (pos.y() - r.top()) / r.height()

    def from_uv(self, u: float, v: float) -> QPointF:
        r = self.map_rect()
        return QPointF(r.left() + u * r.width(), r.top() + v * r.height())

    # -- the editor's callbacks ----------------------------------------------------
    def _changed(self, live: bool, new_stroke: bool) -> None:
        age = self._made.elapsed() if self._made.isValid() else PICTURE_INTERVAL_MS
        if live and self._picture is not None and age < PICTURE_INTERVAL_MS:
            if not self._catch_up.isActive():
                self._catch_up.start(PICTURE_INTERVAL_MS - age)
            self.update()  # the markers move now; the picture follows
        else:
            self._redraw()
        self.lightsChanged.emit(live, new_stroke)

    def _redraw(self) -> None:
        self._catch_up.stop()
        self._picture = None
        self.update()

    def _selected(self, index: int | None) -> None:
        self.update()
        self.selectionChanged.emit(-1 if index is None else index)

    # -- input -------------------------------------------------------------------------
    def mousePressEvent(self, event) -> None:
        u, v = self.to_uv(event.pos())
        if not (0.0 <= u <= 1.0 and 0.0 <= v <= 1.0):
            return
        if event.button() == Qt.MouseButton.RightButton:
            self.editor.remove_at(u, v)
        elif event.button() == Qt.MouseButton.LeftButton:
            self.editor.press(u, v)

    def mouseMoveEvent(self, event) -> None:
        self.editor.drag(*self.to_uv(event.pos()))

    def mouseReleaseEvent(self, event) -> None:
        if event.button() == Qt.MouseButton.LeftButton:
            self.editor.release()

    def wheelEvent(self, event) -> None:
        shift = bool(event.modifiers() & Qt.KeyboardModifier.ShiftModifier)
        self.editor.scroll(event.angleDelta().y() / 120.0, intensity=shift, at=self.to_uv(event.pos()))
        event.accept()

    def keyPressEvent(self, event) -> None:
        if event.key() in (Qt.Key.Key_Delete, Qt.Key.Key_Backspace):
            self.editor.remove_selected()
        else:
            super().keyPressEvent(event)

    # -- drawing -------------------------------------------------------------------------
    def picture(self) -> QImage:
        """The tone-mapped light map (the host kit's picture, the same as GIMP's)."""
        if self._picture is None:
            w, h = light_map_picture.PICTURE_SIZE
            data = light_map_picture.map_rgb(self.light_map, w, h)
            self._picture = QImage(data, w, h, 3 * w, QImage.Format_RGB888).copy()
            self._made.start()
        return self._picture

    def paintEvent(self, event) -> None:
        p = QPainter(self)
        p.setRenderHint(QPainter.Antialiasing)
        p.setRenderHint(QPainter.SmoothPixmapTransform)
        r = self.map_rect()
        p.drawImage(r, self.picture())
        p.setPen(QPen(QColor(255, 255, 255, 70), 1, Qt.PenStyle.DashLine))
        p.drawLine(self.from_uv(0.5, 0.0), self.from_uv(0.5, 1.0))  # straight ahead of the camera
        p.drawLine(self.from_uv(0.25, 0.0), self.from_uv(0.25, 1.0))
        p.drawLine(self.from_uv(0.75, 0.0), self.from_uv(0.75, 1.0))
        p.setPen(QColor(255, 255, 255, 150))
        font = p.font()
        font.setPointSizeF(max(6.0, font.pointSizeF() * 0.75))
        p.setFont(font)
        # Where a light there sits, and so where its shadow falls (the opposite way).
        p.drawText(QRectF(r.left(), r.bottom() - 16, r.width(), 14), Qt.AlignmentFlag.AlignHCenter, "behind the object")
        metrics = p.fontMetrics()
        if (
            2 * metrics.horizontalAdvance("behind you") + metrics.horizontalAdvance("behind the object") + 24
            < r.width()
        ):
            p.drawText(QRectF(r.left() + 3, r.bottom() - 16, r.width(), 14), Qt.AlignmentFlag.AlignLeft, "behind you")
            p.drawText(QRectF(r.left(), r.bottom() - 16, r.width() - 3, 14), Qt.AlignmentFlag.AlignRight, "behind you")
        p.drawText(QRectF(r.left(), r.top() + 2, r.width(), 14), Qt.AlignmentFlag.AlignHCenter, "zenith (short shadow)")
        p.drawText(
            QRectF(r.left(), r.bottom() - 30, r.width(), 14), Qt.AlignmentFlag.AlignHCenter, "horizon (long shadow)"
        )
        p.setClipRect(r)
        for i, light in enumerate(self.light_map):
            self._draw_marker(p, r, light, i == self.selected)
        p.setClipping(False)
        p.setPen(QColor(90, 90, 90))
        p.setBrush(Qt.BrushStyle.NoBrush)
        p.drawRect(r)
        p.end()

    def _draw_marker(self, p: QPainter, r: QRectF, light: lm.GaussianLight, selected: bool) -> None:
        """A light's marker (the host kit's, as GIMP draws it): its true extent, or a dotted ring where it is
        smaller than that; its centre; its size beside it."""
        m = light_map_picture.marker(light, round(r.width()), round(r.height()))
        colour = QColor(255, 200, 40) if selected else QColor(255, 255, 255)
        pen = QPen(colour, 2 if selected else 1, Qt.PenStyle.SolidLine if m.true_size else Qt.PenStyle.DotLine)
        p.setPen(pen)
        p.setBrush(Qt.BrushStyle.NoBrush)
        for shift in (-r.width(), 0.0, r.width()):  # the map wraps around in azimuth
            for line in m.outline:
                p.drawPolyline(QPolygonF([QPointF(r.left() + x + shift, r.top() + y) for x, y in line]))
        centre = QPointF(r.left() + m.centre[0], r.top() + m.centre[1])
        p.setPen(QPen(QColor(40, 40, 40), 1))
        p.setBrush(colour)
        p.drawEllipse(centre, 3.0, 3.0)
        wide = p.fontMetrics().horizontalAdvance(m.label)
        x = m.label_x if m.label_x + wide <= r.width() else m.label_x_left - wide
        box = QRectF(r.left() + x, centre.y() - 8, wide + 2, 16)
        p.setPen(QColor(20, 20, 30))  # a shade under the text, for the bright sky behind it
        p.drawText(box.translated(1, 1), Qt.AlignmentFlag.AlignLeft | Qt.AlignmentFlag.AlignVCenter, m.label)
        p.setPen(colour)
        p.drawText(box, Qt.AlignmentFlag.AlignLeft | Qt.AlignmentFlag.AlignVCenter, m.label)
