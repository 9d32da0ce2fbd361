"""The Krita host as the docker sees it: the active document, its source, the shadow layer, its annotations."""

from __future__ import annotations

from collections.abc import Callable
from typing import TYPE_CHECKING

from PyQt5.QtCore import QAbstractItemModel, QTimer
from PyQt5.QtWidgets import QAbstractItemView, QDockWidget, QListView, QMainWindow, QTreeView

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
HISTORY_DOCKER = "History"  # the object name of Krita's Undo History docker
# the signals by which the Undo History docker's model follows its undo stack (Krita 5.1 resets it at each new
# command, undo and redo)
HISTORY_SIGNALS = ("modelReset", "rowsInserted", "rowsRemoved", "dataChanged", "layoutChanged")


class HistoryStamp:
    """A counter of the changes to the undo history that the active window's Undo History docker shows: a new
    command (a brush stroke, an erase, a fill, a selection, a layer added or removed), an undo, a redo, another
    document's history shown. Krita 5.1's scripting API has no pixel-change signal or counter on a layer or a
    document (``Document.modified()`` stays true from the first change until a save), and its Undo History
    docker's model, hidden or not, is reset at each change of the undo stack it shows, whichever window made
    the change: while the counter stands still, no undoable change was made to the active window's document.
    ``Node.setPixelData`` makes no undo command: a script's write goes unseen until the next command."""

    def __init__(self, active_window: Callable[[], QMainWindow | None]) -> None:
        self.count = 0
        self._active_window = active_window
        # the windows seen, each with its Undo History docker's model (None: none), found once a window (a search
        # of a window's widgets takes 30 to 45 ms)
        self._windows: list[tuple[QMainWindow, QAbstractItemModel | None]] = []

    def now(self) -> tuple[int, int] | None:
        """The active window (the order in which it was first seen) and the counter now; None where that window
        has no Undo History docker (nothing to go by)."""
        window = self._active_window()
        if window is None:
            return None
        seen = next((i for i, (w, _) in enumerate(self._windows) if w is window), None)
        if seen is None:  # a window not seen before: changes may lie behind
            model = _docker_model(window, HISTORY_DOCKER, QListView)
            seen = len(self._windows)
            self._windows.append((window, model))
            if model is not None:
                for name in HISTORY_SIGNALS:
                    getattr(model, name).connect(self._changed)
            self.count += 1
        return (seen, self.count) if self._windows[seen][1] is not None else None

    def _changed(self, *_: object) -> None:
        self.count += 1


def _docker_model(
    window: QMainWindow | None, name: str, view_type: type[QAbstractItemView]
) -> QAbstractItemModel | None:
    """The model of the ``view_type`` view in ``window``'s docker named ``name`` (None: no window, no such
    docker)."""
    if window is None:
        return None
    for dock in window.findChildren(QDockWidget):
        if dock.objectName() == name:
            view = dock.findChild(view_type)
            return view.model() if view is not None else None
    return None


class KritaHost:
    """Binds the document adapters to a running Krita (``Krita.instance()``)."""

    def __init__(self, krita: Krita) -> None:
        self.krita = krita
        self.writer = LayerWriter()
        self._watched: list[object] = []  # the undo and redo actions followed (Krita makes them per window)
        self.history = HistoryStamp(self._active_qwindow)
        # the source last read and the history's count before that read; the image without its shadow last taken
        # for the preview (the source it was taken for, its side, the count before, the image): both still hold
        # while the count stands still (the plug-in's own commands move it on: see _own_commands)
        self._read: tuple[Source, tuple[int, int] | None] | None = None
        self._shot: tuple[Source, int, tuple[int, int] | None, tuple[int, int, bytes]] | None = None

    def active_document(self) -> Document | None:
        return self.krita.activeDocument()

    def read_source(self, document: Document | None) -> Source:
        stamp = self.history.now()
        source = read_source(document)
        self._read = (source, stamp)
        return source

    def refresh_source(self, source: Source) -> Source:
        """The same cutout read again: ``source`` where its alpha is unchanged, else one with the new alpha.
        ``source`` itself, unread, where it was the last source read and no undoable change was made since
        (:class:`HistoryStamp`): the read costs 340 to 390 ms for a 4000 x 3000 float layer (docs/krita.md, *The
        cutout read again*)."""
        stamp = self.history.now()
        if stamp is not None and self._read is not None and self._read[0] is source and self._read[1] == stamp:
            return source
        fresh = refresh_source(source)
        self._read = (fresh, stamp)
        return fresh

    def _own_commands(self, before: tuple[int, int] | None) -> None:
        """The plug-in's own undo commands (its layer added, replaced) moved the history's count on: what was
        current before them (the cutout read, the image without its shadow) is current after them."""
        after = self.history.now()
        if self._read is not None and self._read[1] is not None and self._read[1] == before:
            self._read = (self._read[0], after)
        if self._shot is not None and self._shot[2] is not None and self._shot[2] == before:
            self._shot = (*self._shot[:2], after, self._shot[3])

    def write(
        self, source: Source, pixels: bytes, rect: tuple[int, int, int, int], new_step: bool, blend: str
    ) -> WriteResult:
        before = self.history.now()
        result = self.writer.write(source.document, source.node, pixels, rect, new_step, blend)
        if result.created:
            self._own_commands(before)
            # With a view, Krita makes the added layer active through a queued signal, after the writer's
            # setActiveNode: set the source active again once the event loop has delivered it, so the next
            # brush stroke lands on the cutout, not on its shadow.
            QTimer.singleShot(0, lambda: source.document.setActiveNode(source.node))
        return result

    def preview_background(self, source: Source, side: int) -> tuple[int, int, bytes]:
        """The image without the source's shadow, at most ``side`` pixels a side: (width, height, RGBA)."""
        stamp = self.history.now()
        shot = preview_background(source.document, source.node, side)
        self._shot = (source, side, stamp, shot)
        return shot

    def _background_kept(self, source: Source, side: int) -> tuple[int, int, bytes] | None:
        """The image without the source's shadow last taken, where it is of this source at this side and no
        undoable change was made since (at 16 bit and float Krita's thumbnail of a 2000 x 2000 image takes
        about 150 ms)."""
        shot, stamp = self._shot, self.history.now()
        if shot is None or stamp is None or shot[0] is not source or shot[1:3] != (side, stamp):
            return None
        return shot[3]

    def begin_drag(self, source: Source, side: int) -> tuple[tuple[int, int, bytes], WriteResult | None]:
        """A light drag starts: its undo step (the shadow layer replaced by a copy of itself, which the drag then
        writes in place; None where there is no shadow layer) and the preview's background, the image without its
        shadow at most ``side`` pixels a side, taken while the shadow layer is out of the image (no clone), or the
        one last taken where nothing changed since (:meth:`_background_kept`)."""
        kept = self._background_kept(source, side)
        stamp = self.history.now()
        shot: list[tuple[int, int, bytes]] = [kept] if kept is not None else []

        def take() -> None:
            if kept is None:
                shot.append(projection_thumbnail(source.document, side))
                self._shot = (source, side, stamp, shot[0])

        result = self.writer.take_over(source.document, source.node, take)
        if result is None:
            return (kept if kept is not None else self.preview_background(source, side)), None
        self._own_commands(stamp)
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
        layers = _docker_model(self._active_qwindow(), LAYERS_DOCKER, QTreeView)
        if layers is not None and not any(layers is known for known in self._watched):
            self._watched.append(layers)
            # Krita adds the layer's row, then activates it, through events posted in that order: after both
            layers.rowsInserted.connect(lambda *_: QTimer.singleShot(0, changed))

    def _active_qwindow(self) -> QMainWindow | None:
        window = self.krita.activeWindow()
        return window.qwindow() if window is not None else None

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
