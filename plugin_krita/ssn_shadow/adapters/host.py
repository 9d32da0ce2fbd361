"""The Krita host as the docker sees it: the active document, its source, the shadow layer, its annotations."""

from __future__ import annotations

from typing import TYPE_CHECKING

from PyQt5.QtCore import QTimer

if TYPE_CHECKING:
    from krita import Document, Krita

from .krita_document import (
    LayerWriter,
    Source,
    WriteResult,
    horizontal_guides,
    preview_background,
    read_annotation,
    read_source,
    write_annotation,
)


class KritaHost:
    """Binds the document adapters to a running Krita (``Krita.instance()``)."""

    def __init__(self, krita: Krita) -> None:
        self.krita = krita
        self.writer = LayerWriter()

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

    def horizontal_guides(self, document: Document | None) -> list[float]:
        return horizontal_guides(document)

    def is_open(self, document: Document) -> bool:
        """``document`` is still open in Krita (not closed)."""
        return any(open_document == document for open_document in self.krita.documents())

    def annotation(self, document: Document, kind: str) -> bytes:
        return read_annotation(document, kind)

    def set_annotation(self, document: Document, kind: str, description: str, data: bytes) -> None:
        write_annotation(document, kind, description, data)
