"""The Krita host as the docker sees it: the active document, its source, the shadow layer, its annotations."""

from __future__ import annotations

from collections.abc import Callable
from typing import TYPE_CHECKING

from PyQt5.QtCore import QAbstractItemModel, QTimer
from PyQt5.QtWidgets import QDockWidget, QTreeView

if TYPE_CHECKING:
    from krita import Document, Krita

from .krita_document import (
    LayerWriter,
    Source,
    WriteResult,
    horizontal_guides,
    keep_source_active,
    preview_background,
    projection_thumbnail,
    read_annotation,
    read_source,
    refresh_source,
    shadow_layer_id,
    write_annotation,
)


LAYERS_DOCKER = "KisLayerBox"  # the object name of Krita's Layers docker


class KritaHost:
    """Binds the document adapters to a running Krita (``Krita.instance()``)."""

    def __init__(self, krita: Krita) -> None:
        self.krita = krita
        self.writer = LayerWriter()
        self._watched: list[object] = []  # the undo and redo actions followed (Krita makes them per window)

    def active_document(self) -> Document | None:
        return self.krita.activeDocument()

    def read_source(self, document: Document | None) -> Source:
        return read_source(document)

    def refresh_source(self, source: Source) -> Source:
        """The same cutout read again: ``source`` where its alpha is unchanged, else one with the new alpha."""
        return refresh_source(source)

    def write(
        self, source: Source, pixels: bytes, rect: tuple[int, int, int, int], new_step: bool, blend: str
    ) -> WriteResult:
        result = self.writer.write(source.document, source.node, pixels, rect, new_step, blend)
        if result.created:
            # With a view, Krita makes the added layer active through a queued signal, after the writer's
            # setActiveNode: set the source active again once the event loop has delivered it, so the next
            # brush stroke lands on the cutout, not on its shadow.
            QTimer.singleShot(0, lambda: source.document.setActiveNode(source.node))
        return result

    def preview_background(self, source: Source, side: int) -> tuple[int, int, bytes]:
        """The image without the source's shadow, at most ``side`` pixels a side: (width, height, RGBA)."""
        return preview_background(source.document, source.node, side)

    def begin_drag(self, source: Source, side: int) -> tuple[tuple[int, int, bytes], WriteResult | None]:
        """A light drag starts: its undo step (the shadow layer replaced by a copy of itself, which the drag then
        writes in place; None where there is no shadow layer) and the preview's background, the image without its
        shadow at most ``side`` pixels a side, taken while the shadow layer is out of the image (no clone)."""
        shot: list[tuple[int, int, bytes]] = []
        result = self.writer.take_over(
            source.document, source.node, lambda: shot.append(projection_thumbnail(source.document, side))
        )
        if result is None:
            return preview_background(source.document, source.node, side), None
        QTimer.singleShot(0, lambda: source.document.setActiveNode(source.node))  # as after :meth:`write`
        return shot[0], result

    def shadow_layer_id(self, source: Source) -> str | None:
        """The unique id of the source's shadow layer now in the image, or None."""
        return shadow_layer_id(source.node)

    def keep_source_active(self, source: Source) -> None:
        """The source active again where the active layer is its shadow layer."""
        keep_source_active(source.document, source.node)

    def watch_history(self, changed: Callable[[], None]) -> None:
        """Call ``changed`` after each undo and redo through Krita's actions (Ctrl+Z, Ctrl+Shift+Z, the Edit
        menu), once Krita has carried it out and activated a layer through its event loop; and after each layer
        added to the image of the active window (a step chosen in the Undo History docker, which goes to it
        without those actions, and any other undo or redo that brings a layer back), once Krita has activated it.
        Krita's scripting API has no undo or layer signal: the layers are the Layers docker's model's rows."""
        for name in ("edit_undo", "edit_redo"):
            action = self.krita.action(name)
            if action is None or any(action is known for known in self._watched):
                continue
            self._watched.append(action)
            action.triggered.connect(lambda *_: QTimer.singleShot(0, lambda: self._after_history(changed)))
        layers = self._layers_model()
        if layers is not None and not any(layers is known for known in self._watched):
            self._watched.append(layers)
            # Krita adds the layer's row, then activates it, through events posted in that order: after both
            layers.rowsInserted.connect(lambda *_: QTimer.singleShot(0, changed))

    def _layers_model(self) -> QAbstractItemModel | None:
        """The model of the active window's Layers docker (None: no window, or no such docker)."""
        window = self.krita.activeWindow()
        if window is None:
            return None
        for dock in window.qwindow().findChildren(QDockWidget):
            if dock.objectName() == LAYERS_DOCKER:
                view = dock.findChild(QTreeView)
                return view.model() if view is not None else None
        return None

    def _after_history(self, changed: Callable[[], None]) -> None:
        """Krita carries an undo out in its image's strokes, then activates a layer through a queued signal."""
        document = self.active_document()
        if document is not None:
            document.waitForDone()
        QTimer.singleShot(0, changed)

    def horizontal_guides(self, document: Document | None) -> list[float]:
        return horizontal_guides(document)

    def open_active_document(self) -> Document | None:
        """The active document where it is still open (Krita 5.1 names a window's closed document its active
        one until another view is activated)."""
        document = self.active_document()
        return document if document is not None and self.is_open(document) else None

    def watch_closing(self, closed: Callable[[], None]) -> None:
        """Call ``closed`` after each view or document Krita closes, once Krita has removed it (the docker's
        ``canvasChanged`` does not come when a window's last view closes)."""
        notifier = self.krita.notifier()
        notifier.setActive(True)  # its signals come only while it is active
        notifier.viewClosed.connect(lambda *_: QTimer.singleShot(0, closed))
        notifier.imageClosed.connect(lambda *_: QTimer.singleShot(0, closed))

    def is_open(self, document: Document) -> bool:
        """``document`` is still open in Krita (not closed)."""
        return any(open_document == document for open_document in self.krita.documents())

    def annotation(self, document: Document, kind: str) -> bytes:
        return read_annotation(document, kind)

    def set_annotation(self, document: Document, kind: str, description: str, data: bytes) -> None:
        write_annotation(document, kind, description, data)
