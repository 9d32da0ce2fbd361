"""The Krita host as the controller sees it: the active document, its source, the shadow layer."""

from __future__ import annotations

from typing import Any

from .krita_document import LayerWriter, Source, WriteResult, read_source


class KritaHost:
    """Binds the document adapters to a running Krita (``Krita.instance()``)."""

    def __init__(self, krita: Any) -> None:
        self.krita = krita
        self.writer = LayerWriter()

    def active_document(self) -> Any:
        return self.krita.activeDocument()

    def read_source(self, document: Any) -> Source:
        return read_source(document)

    def write(self, source: Source, pixels: bytes, rect: tuple[int, int, int, int], new_step: bool) -> WriteResult:
        return self.writer.write(source.document, source.node, pixels, rect, new_step)
