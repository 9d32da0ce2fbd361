"""The Krita host as the docker sees it: the active document, its source, the shadow layer, its annotations."""

from __future__ import annotations

from collections.abc import Callable
from typing import TYPE_CHECKING

from PyQt5.QtCore import QTimer

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
    shadow_layer_id,
    write_annotation,
)


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
        """Call ``changed`` after each undo and redo (Ctrl+Z, the Edit menu, the Undo History docker's buttons
        trigger these actions), once Krita has carried it out and activated a layer through its event loop."""
        for name in ("edit_undo", "edit_redo"):
            action = self.krita.action(name)
            if action is None or any(action is known for known in self._watched):
                continue
            self._watched.append(action)
            action.triggered.connect(lambda *_: QTimer.singleShot(0, lambda: self._after_history(changed)))

    def _after_history(self, changed: Callable[[], None]) -> None:
        """Krita carries an undo out in its image's strokes, then activates a layer through a queued signal."""
        document = self.active_document()
        if document is not None:
            document.waitForDone()
        QTimer.singleShot(0, changed)

    def horizontal_guides(self, document: Document | None) -> list[float]:
        return horizontal_guides(document)

    def is_open(self, document: Document) -> bool:
        """``document`` is still open in Krita (not closed)."""
        return any(open_document == document for open_document in self.krita.documents())

    def annotation(self, document: Document, kind: str) -> bytes:
        return read_annotation(document, kind)

    def set_annotation(self, document: Document, kind: str, description: str, data: bytes) -> None:
        write_annotation(document, kind, description, data)
