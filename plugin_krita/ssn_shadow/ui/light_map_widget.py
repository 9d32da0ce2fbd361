"""The light map editor: the upper hemisphere drawn 2:1, the camera's forward direction in the middle.

Click to add a light, drag to move it, wheel for softness, right-click or
Delete to remove. The model is the engine's ``LightMap``; this widget only
draws it and turns mouse input into its edit calls.
"""

from __future__ import annotations

import math
import time

from PyQt5.QtCore import QPointF, QRectF, QSize, Qt, pyqtSignal
from PyQt5.QtGui import QColor, QImage, QPainter, QPen
from PyQt5.QtWidgets import QSizePolicy, QWidget

from ..shared import light_map as lm
from .map_image import map_rgb

WHEEL_STEP = 1.25  # softness factor per wheel notch
STROKE_GAP_S = 0.6  # wheel turns further apart than this start a new undo step


class LightMapWidget(QWidget):
    """Editor of one ``LightMap``."""

    lightsChanged = pyqtSignal(bool, bool)  # dragging (live), stroke_started (new undo step)
    selectionChanged = pyqtSignal(int)  # index of the selected light, -1 for none

    def __init__(self, light_map: lm.LightMap | None = None, parent: QWidget | None = None) -> None:
        super().__init__(parent)
        self.light_map = light_map if light_map is not None else lm.preset(lm.DEFAULT_PRESET)
        self.selected: int | None = 0 if len(self.light_map) else None
        self._drag: int | None = None
        self._moved = False
        self._last_wheel = 0.0
        self._image: QImage | None = None
        self.setFocusPolicy(Qt.ClickFocus)
        self.setMouseTracking(False)
        self.setMinimumSize(160, 80)
        policy = QSizePolicy(QSizePolicy.Expanding, QSizePolicy.Preferred)
        policy.setHeightForWidth(True)
        self.setSizePolicy(policy)
        self.setToolTip("Click: add a light · drag: move · wheel: softness · right-click or Delete: remove")

    # -- geometry ------------------------------------------------------------------
    def sizeHint(self) -> QSize:
        return QSize(320, 160)

    def hasHeightForWidth(self) -> bool:
        return True

    def heightForWidth(self, width: int) -> int:
        return max(80, width // 2)

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

    # -- model -----------------------------------------------------------------------
    def set_light_map(self, light_map: lm.LightMap) -> None:
        self.light_map = light_map
        self._select(0 if len(light_map) else None)
        self._changed(False, True)

    def _select(self, index: int | None) -> None:
        if index != self.selected:
            self.selected = index
            self.selectionChanged.emit(-1 if index is None else index)
        self.update()

    def _changed(self, dragging: bool, stroke_started: bool) -> None:
        self._image = None
        self.update()
        self.lightsChanged.emit(dragging, stroke_started)

    def delete_selected(self) -> None:
        if self.selected is not None and self.selected < len(self.light_map):
            self.light_map.delete(self.selected)
            self._select(None)
            self._changed(False, True)

    def set_softness(self, softness: float, stroke_started: bool = False) -> None:
        """The selected light's softness (a slider moved); ``stroke_started``: the first move of a drag."""
        if self.selected is not None:
            self.light_map.resize(self.selected, softness)
            self._changed(True, stroke_started)

    def set_intensity(self, intensity: float, stroke_started: bool = False) -> None:
        """The selected light's intensity (a slider moved)."""
        if self.selected is not None:
            self.light_map.reweight(self.selected, intensity)
            self._changed(True, stroke_started)

    # -- input -------------------------------------------------------------------------
    def mousePressEvent(self, event) -> None:
        u, v = self.to_uv(event.pos())
        if not (0.0 <= u <= 1.0 and 0.0 <= v <= 1.0):
            return
        hit = self.light_map.hit_test(u, v)
        if event.button() == Qt.RightButton:
            if hit is not None:
                self.light_map.delete(hit)
                self._select(None)
                self._changed(False, True)
            return
        if event.button() != Qt.LeftButton:
            return
        if hit is None:
            try:
                hit = self.light_map.add(u, v)
            except lm.LightMapError:
                return  # at most MAX_LIGHTS lights
            self._select(hit)
            self._drag, self._moved = hit, True
            self._changed(True, True)
            return
        self._select(hit)
        self._drag, self._moved = hit, False

    def mouseMoveEvent(self, event) -> None:
        if self._drag is None:
            return
        u, v = self.to_uv(event.pos())
        self.light_map.move(self._drag, u, v)
        first = not self._moved
        self._moved = True
        self._changed(True, first)

    def mouseReleaseEvent(self, event) -> None:
        self._drag = None

    def wheelEvent(self, event) -> None:
        u, v = self.to_uv(event.pos())
        target = self.light_map.hit_test(u, v)
        if target is None:
            target = self.selected
        if target is None:
            return
        steps = event.angleDelta().y() / 120.0
        light = self.light_map.lights[target]
        self.light_map.resize(target, light.softness * WHEEL_STEP**steps)
        self._select(target)
        now = time.monotonic()
        started = now - self._last_wheel > STROKE_GAP_S
        self._last_wheel = now
        self._changed(True, started)
        event.accept()

    def keyPressEvent(self, event) -> None:
        if event.key() in (Qt.Key_Delete, Qt.Key_Backspace):
            self.delete_selected()
        else:
            super().keyPressEvent(event)

    # -- drawing -------------------------------------------------------------------------
    def map_image(self) -> QImage:
        if self._image is None:
            w, h = 96, 48
            data = map_rgb(self.light_map, w, h)
            self._image = QImage(data, w, h, 3 * w, QImage.Format_RGB888).copy()
        return self._image

    def paintEvent(self, event) -> None:
        p = QPainter(self)
        p.setRenderHint(QPainter.Antialiasing)
        p.setRenderHint(QPainter.SmoothPixmapTransform)
        r = self.map_rect()
        p.drawImage(r, self.map_image())
        p.setPen(QPen(QColor(255, 255, 255, 70), 1, Qt.DashLine))
        p.drawLine(self.from_uv(0.5, 0.0), self.from_uv(0.5, 1.0))  # straight ahead of the camera
        p.drawLine(self.from_uv(0.25, 0.0), self.from_uv(0.25, 1.0))
        p.drawLine(self.from_uv(0.75, 0.0), self.from_uv(0.75, 1.0))
        p.setPen(QColor(255, 255, 255, 150))
        font = p.font()
        font.setPointSizeF(max(6.0, font.pointSizeF() * 0.75))
        p.setFont(font)
        # Where a light there sits, and so where its shadow falls (the opposite way).
        p.drawText(QRectF(r.left(), r.bottom() - 16, r.width(), 14), Qt.AlignHCenter, "behind the object")
        p.drawText(QRectF(r.left() + 3, r.bottom() - 16, r.width(), 14), Qt.AlignLeft, "behind you")
        p.drawText(QRectF(r.left(), r.bottom() - 16, r.width() - 3, 14), Qt.AlignRight, "behind you")
        p.drawText(QRectF(r.left(), r.top() + 2, r.width(), 14), Qt.AlignHCenter, "zenith (short shadow)")
        p.drawText(QRectF(r.left(), r.bottom() - 30, r.width(), 14), Qt.AlignHCenter, "horizon (long shadow)")
        for i, light in enumerate(self.light_map):
            c = self.from_uv(light.u, light.v)
            radius = max(4.0, light.radius * r.height())
            selected = i == self.selected
            p.setPen(QPen(QColor(255, 200, 40) if selected else QColor(40, 40, 40), 2 if selected else 1))
            p.setBrush(QColor(255, 255, 255, 40))
            p.drawEllipse(c, radius, radius)
            p.setBrush(QColor(255, 200, 40) if selected else QColor(255, 255, 255))
            p.drawEllipse(c, 3.0, 3.0)
        p.setPen(QColor(90, 90, 90))
        p.setBrush(Qt.NoBrush)
        p.drawRect(r)
        p.end()


def softness_to_slider(softness: float) -> int:
    """Log-scale slider position 0..100 for softness in Table 1's range."""
    lo, hi = lm.SOFTNESS_RANGE
    return round(100 * math.log(softness / lo) / math.log(hi / lo))


def slider_to_softness(position: int) -> float:
    lo, hi = lm.SOFTNESS_RANGE
    return lo * (hi / lo) ** (position / 100.0)
