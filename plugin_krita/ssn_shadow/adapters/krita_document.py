"""Krita documents and layers: read the source alpha, write the shadow layer below it.

Only Krita's Python API (libkis) is used; the objects come in as arguments,
so this module imports nothing from Krita and its logic is testable with
stand-ins.

Undo, as measured in Krita 5.1.5: ``Node.addChildNode`` and ``Node.remove``
are undoable commands, ``Node.setPixelData`` is not. So a new shadow layer is
built while it is still detached (pixels, Multiply blend mode) and then added
in one command: one Ctrl+Z removes it. Generating again replaces the old
shadow layer by a new one in the same place (remove + add: two undo steps,
the first of which leaves no shadow, the second brings the previous one back).
Live updates during one drag write in place into the layer that drag added,
so they do not flood the undo stack. ``Node.setBlendingMode`` is an undo
command of its own, even on a detached node: a new layer is Normal, right for
a black shadow (:func:`pixel_format.blend_mode`), so a first black shadow is
one undo step; a coloured one adds an invisible blend-mode step. A
replacement is a copy of the old layer, which keeps its mode unless the
colour needs the other of Normal and Multiply (a mode the user picked is kept).
"""

from __future__ import annotations

import hashlib
from collections.abc import Callable
from dataclasses import dataclass, replace
from functools import cached_property
from typing import TYPE_CHECKING

if TYPE_CHECKING:
    from krita import Document, Node

from ..shared import camera_rules
from .pixel_format import (
    PixelFormat,
    Rect,
    clip_rect,
    extract_alpha,
    opaque_everywhere,
    pixel_format,
    place_rows,
    rect_difference,
)

SHADOW_PREFIX = "Shadow: "


class SourceError(RuntimeError):
    """No usable source (no document, no layer, a shadow layer...); the message is for people."""


@dataclass
class Source:
    """The cutout to cast a shadow from: a canvas-sized alpha plane and the layer it belongs to."""

    document: Document
    node: Node
    node_id: str
    name: str
    alpha: bytes
    dtype: str
    width: int
    height: int
    from_selection: bool
    layer_format: PixelFormat  # the document's: the shadow layer is written in it
    profile: str
    region: Rect | None = None  # the layer's part of the canvas the alpha was read from (None: a selection)
    opacity: float = 1.0  # the layer's opacity times its groups' (a selection: 1): the alpha does not carry it

    @cached_property
    def key(self) -> str:
        """Identifies the alpha content (to reuse the engine's cutout and AO); hashed once (a 2000 x 2000 float
        alpha takes 15 ms, which each render after a light move would otherwise spend again)."""
        digest = hashlib.blake2b(self.alpha, digest_size=16).hexdigest()
        return f"{self.node_id}:{self.width}x{self.height}:{self.dtype}:{self.opacity:.4f}:{digest}"


def shown_opacity(node: Node) -> float:
    """How strongly ``node``'s pixels show: its opacity times its groups' (0..1; the image's root counts 1)."""
    opacity, item = 1.0, node
    while item is not None and item.parentNode() is not None:
        opacity *= min(max(item.opacity() / 255.0, 0.0), 1.0)
        item = item.parentNode()
    return opacity


def node_id(node: Node) -> str:
    return node.uniqueId().toString()


def shadow_name(source_name: str) -> str:
    return SHADOW_PREFIX + source_name


def read_source(document: Document | None) -> Source:
    """The active selection's alpha if there is one, else the active layer's alpha."""
    if document is None:
        raise SourceError("Open an image first.")
    layer_format = pixel_format(document.colorModel(), document.colorDepth())
    node = document.activeNode()
    if node is None or node.parentNode() is None:
        raise SourceError("Select the layer that holds the cutout.")
    if node.name().startswith(SHADOW_PREFIX):
        node = _source_of_shadow(node)
    selection = document.selection()
    from_selection = selection is not None and selection.width() > 0 and selection.height() > 0
    w, h = document.width(), document.height()
    alpha, dtype, region = _read_alpha(document, node, from_selection)
    assert alpha is not None, "read without a known source"
    return Source(
        document,
        node,
        node_id(node),
        node.name(),
        alpha,
        dtype,
        w,
        h,
        from_selection,
        layer_format,
        document.colorProfile(),
        region,
        1.0 if from_selection else shown_opacity(node),
    )


def refresh_source(source: Source) -> Source:
    """The same cutout read again (the layer's alpha, or the document's selection where the source is a
    selection and one is still made): ``source`` itself where its alpha is unchanged (its key is not hashed
    again), else a Source with the new alpha. A layer no longer in the image, or a selection source whose
    selection is gone, keeps ``source``. SourceError where the cutout is now empty or opaque everywhere.

    A libkis node has no change counter or signal, so the alpha is read again and compared: on a 4000 x 3000
    layer 63 to 70 ms at 8 bit, 338 to 394 ms at 32-bit float (docs/krita.md, *The cutout read again*); the
    docker does it once per edit (the start of a drag, a click), not per frame, and only where Krita's undo
    history changed since the last read (``host.HistoryStamp``)."""
    document, node = source.document, source.node
    if source.from_selection:
        selection = document.selection()
        if selection is None or selection.width() <= 0 or selection.height() <= 0:
            return source
    elif node.parentNode() is None:
        return source
    w, h = document.width(), document.height()
    layer_format = pixel_format(document.colorModel(), document.colorDepth())
    opacity = 1.0 if source.from_selection else shown_opacity(node)
    alpha, dtype, region = _read_alpha(document, node, source.from_selection, source)
    if alpha is None and opacity == source.opacity:
        return source
    alpha = source.alpha if alpha is None else alpha
    return replace(
        source, alpha=alpha, dtype=dtype, width=w, height=h, layer_format=layer_format, region=region, opacity=opacity
    )


def _read_alpha(
    document: Document, node: Node, from_selection: bool, known: Source | None = None
) -> tuple[bytes | None, str, Rect | None]:
    """The cutout's canvas-sized alpha plane, its dtype and the layer's region on the canvas (None: the
    selection's); with ``known``, no plane (None) where that source's alpha is the same."""
    w, h = document.width(), document.height()
    if from_selection:
        selection = document.selection()
        assert selection is not None, "the caller checked that there is a selection"
        alpha, dtype, region = bytes(selection.pixelData(0, 0, w, h)), "uint8", None
        whole = (
            "The selection covers the whole canvas, so its shadow would darken the whole "
            "picture. Select just the object, or deselect (Ctrl+Shift+A) to use the layer's alpha."
        )
        if known is not None and (known.dtype, known.width, known.height) == (dtype, w, h) and known.alpha == alpha:
            return None, dtype, region
    else:
        node_format = pixel_format(node.colorModel(), node.colorDepth())
        b = node.bounds()
        region = clip_rect(b.x(), b.y(), b.width(), b.height(), w, h)
        x, y, bw, bh = region
        if bw == 0 or bh == 0:
            raise SourceError(f"The layer '{node.name()}' is empty on the canvas: nothing to cast a shadow from.")
        dtype = node_format.dtype
        cut = extract_alpha(bytes(node.projectionPixelData(x, y, bw, bh)), node_format)
        if known is not None and same_plane(known, cut, region, dtype, w, h):
            return None, dtype, region
        alpha = bytes(place_rows(cut, x, y, bw, bh, w, h, node_format.itemsize))
        whole = (
            f"The layer '{node.name()}' is opaque over the whole canvas, so it holds no cutout. "
            "Erase the background around the object, or select the object."
        )
    if opaque_everywhere(alpha, dtype):
        raise SourceError(whole)
    return alpha, dtype, region


def same_plane(known: Source, cut: bytes, region: Rect, dtype: str, width: int, height: int) -> bool:
    """Whether ``cut``, the alpha of ``region`` of a ``width`` x ``height`` canvas, is ``known``'s alpha plane:
    the same canvas, dtype and region (the plane is zero outside its region) and the same bytes in it. Row by
    row, without building the new plane (a 4000 x 3000 float plane costs 40 to 150 ms to build)."""
    if (known.width, known.height, known.dtype, known.region) != (width, height, dtype, region):
        return False
    x, y, w, h = region
    itemsize = len(known.alpha) // max(1, width * height)
    row, stride = w * itemsize, width * itemsize
    if len(cut) != row * h:
        return False
    plane = known.alpha
    if x == 0 and w == width:
        return plane[y * stride : (y + h) * stride] == cut
    start = y * stride + x * itemsize
    return all(plane[start + r * stride : start + r * stride + row] == cut[r * row : (r + 1) * row] for r in range(h))


def _source_of_shadow(shadow: Node) -> Node:
    """The layer the shadow was made from: a neighbour (the layer directly above it, or the lowest layer of the
    group) whose :func:`shadow_of` is this shadow."""
    siblings = _parent(shadow).childNodes()
    i = _index_of(siblings, shadow)
    for candidate in siblings[i + 1 : i + 2] + siblings[:1]:
        found = shadow_of(candidate)
        if found is not None and node_id(found) == node_id(shadow):
            return candidate
    raise SourceError("The active layer is a shadow layer; select the cutout's layer instead.")


def _parent(node: Node) -> Node:
    parent = node.parentNode()
    if parent is None:
        raise SourceError(f"The layer '{node.name()}' is no longer in the image.")
    return parent


def _index_of(nodes: list[Node], node: Node) -> int:
    target = node_id(node)
    for i, n in enumerate(nodes):
        if node_id(n) == target:
            return i
    raise SourceError(f"The layer '{node.name()}' is no longer in the image.")


def shadow_of(source_node: Node) -> Node | None:
    """The source's shadow layer (by name): directly below it, or directly above it where the source is the
    lowest layer of its group (where ``LayerWriter`` had to put it); None when there is none."""
    parent = source_node.parentNode()
    if parent is None:
        return None
    siblings = parent.childNodes()
    i = _index_of(siblings, source_node)
    neighbour = i - 1 if i > 0 else 1
    if neighbour < len(siblings) and siblings[neighbour].name() == shadow_name(source_node.name()):
        return siblings[neighbour]
    return None


def shadow_layer_id(source_node: Node) -> str | None:
    """The unique id of the source's shadow layer now in the image (None: none, or the source is gone)."""
    try:
        shadow = shadow_of(source_node)
    except SourceError:
        return None
    return node_id(shadow) if shadow is not None else None


def keep_source_active(document: Document, source_node: Node) -> None:
    """Where the active layer is the source's shadow layer (an undo that brought it back makes it active), make
    the source active again, so that the next brush stroke lands on the cutout."""
    active = document.activeNode()
    try:
        shadow = shadow_of(source_node)
    except SourceError:  # the source is no longer in the image
        return
    if active is not None and shadow is not None and node_id(active) == node_id(shadow):
        document.setActiveNode(source_node)


def _path_of(node: Node) -> list[int]:
    """Child indices from the root down to ``node``."""
    path = []
    parent = node.parentNode()
    while parent is not None:
        path.append(_index_of(parent.childNodes(), node))
        node, parent = parent, parent.parentNode()
    return path[::-1]


def preview_background(document: Document, source_node: Node, side: int) -> tuple[int, int, bytes]:
    """The image as it looks without the source's shadow layer, scaled to at most ``side`` pixels a side:
    (width, height, packed 8-bit RGBA). The shadow is hidden in a clone of the document, so the image, its
    canvas and its undo history never see the change."""
    shadow = shadow_of(source_node)
    if shadow is None:
        return projection_thumbnail(document, side)
    clone = document.clone()
    try:
        node = clone.rootNode()
        for i in _path_of(shadow):
            node = node.childNodes()[i]
        node.setVisible(False)
        clone.refreshProjection()
        return projection_thumbnail(clone, side)
    finally:
        clone.close()


def projection_thumbnail(document: Document, side: int) -> tuple[int, int, bytes]:
    """The document's projection as it is now, scaled to at most ``side`` pixels a side: (width, height, packed
    8-bit RGBA)."""
    from PyQt5.QtCore import Qt
    from PyQt5.QtGui import QImage

    width, height, _ = camera_rules.preview_size(document.width(), document.height(), side)
    if document.colorDepth() == "U8":
        image = document.projection(0, 0, document.width(), document.height())
    else:
        # Krita 5.1 converts a 16-bit or float projection to an image pixel by pixel (a 2000 x 2000 float one took
        # 0.6 to 0.9 s); its thumbnail scales the image down first (0.2 to 0.3 s at any depth, slower than the
        # 8-bit projection's 10 to 60 ms)
        image = document.thumbnail(width, height)
    small = image.scaled(
        width, height, Qt.AspectRatioMode.IgnoreAspectRatio, Qt.TransformationMode.SmoothTransformation
    ).convertToFormat(QImage.Format.Format_RGBA8888)
    bits = small.constBits()
    if bits is None:  # a null image: Krita could not draw the document
        raise RuntimeError("Krita returned no image of the document")
    return width, height, bits.asstring(small.sizeInBytes())  # 4-byte pixels: rows are packed


@dataclass
class WriteResult:
    node: Node
    created: bool
    notice: str = ""
    layer_id: str = ""  # the shadow layer's unique id (Krita keeps it across undo and in the .kra)


class LayerWriter:
    """Writes shadow layers into Krita documents, undoably where Krita allows it."""

    def __init__(self) -> None:
        self._rects: dict[str, Rect] = {}

    def write(
        self,
        document: Document,
        source_node: Node,
        pixels: bytes,
        rect: Rect,
        new_step: bool,
        blend: str = "multiply",
    ) -> WriteResult:
        """Show ``pixels`` (rect x, y, w, h, in the document's pixel format) as the source's shadow, in the blend
        mode ``blend`` ("normal" or "multiply": :func:`pixel_format.blend_mode` of its colour).

        ``new_step``: make this an undo step (a new layer replacing the old one); otherwise
        write in place into the existing shadow layer (live updates within one drag).
        """
        existing = shadow_of(source_node)
        if existing is not None and not new_step:
            self._write_in_place(document, existing, pixels, rect)
            return WriteResult(existing, False, "", node_id(existing))
        if existing is not None:
            # A copy keeps its mode without the extra undo command setBlendingMode would add.
            node = self._copy(existing, source_node)
            self._clear(node, self._rect_of(existing), rect)
        else:
            node = document.createNode(shadow_name(source_node.name()), "paintlayer")
        if node.blendingMode() in ("normal", "multiply") and node.blendingMode() != blend:
            node.setBlendingMode(blend)
        x, y, w, h = rect
        if w > 0 and h > 0:
            node.setPixelData(pixels, x, y, w, h)
        return self._replace(document, source_node, existing, node, rect)

    def take_over(self, document: Document, source_node: Node, while_out: Callable[[], object]) -> WriteResult | None:
        """Replace the source's shadow layer by a copy of itself, the undo step of the writes in place that follow
        (a light drag's): the canvas keeps its pixels. ``while_out()`` runs between the removal and the addition,
        in the same turn of the event loop (the canvas never shows the image without its shadow), while the
        document's projection is the image without its shadow. None, and no call, where there is no shadow layer.

        A replacement costs two recomposites of the whole image (Krita 5.1's ``remove`` and ``addChildNode``), a
        write in place one (``refreshProjection``): taken over when a drag starts, the layer written on release
        costs Krita one.
        """
        existing = shadow_of(source_node)
        if existing is None:
            return None
        return self._replace(
            document, source_node, existing, self._copy(existing, source_node), self._rect_of(existing), while_out
        )

    @staticmethod
    def _copy(shadow: Node, source_node: Node) -> Node:
        """A copy of the shadow layer ``shadow``, named for ``source_node``."""
        node = shadow.duplicate()
        node.setName(shadow_name(source_node.name()))
        return node

    def _replace(
        self,
        document: Document,
        source_node: Node,
        existing: Node | None,
        node: Node,
        rect: Rect,
        while_out: Callable[[], object] = lambda: None,
    ) -> WriteResult:
        """``node``, covering ``rect``, in the place of the shadow layer ``existing`` (None: added below the
        source), ``while_out()`` run between the removal and the addition; the source stays the active layer."""
        self._rects[node_id(node)] = rect
        if existing is not None:
            existing.remove()
        try:
            while_out()
        finally:
            # Node.remove and Node.addChildNode each wait for Krita to recomposite the whole image (Krita 5.1:
            # their commands mark the image's bounds dirty): nothing is left to wait for after them.
            notice = self._insert_below(document, source_node, node)
            document.setActiveNode(source_node)  # Krita makes an added layer active; keep the source active
        return WriteResult(node, True, notice, node_id(node))

    def _rect_of(self, node: Node) -> Rect:
        rect = self._rects.get(node_id(node))
        if rect is None:
            b = node.bounds()
            rect = (b.x(), b.y(), b.width(), b.height())
        return rect

    @staticmethod
    def _clear(node: Node, old: Rect, new: Rect) -> None:
        """Clear the ``old`` rect of ``node`` where the ``new`` one, written next, does not cover it (the new
        pixels overwrite the rest: on float documents a whole clear costs as much as the write)."""
        ps = 0
        for x, y, w, h in rect_difference(old, new):
            ps = ps or len(bytes(node.pixelData(0, 0, 1, 1)))
            node.setPixelData(bytes(w * h * ps), x, y, w, h)

    def _write_in_place(self, document: Document, node: Node, pixels: bytes, rect: Rect) -> None:
        self._clear(node, self._rect_of(node), rect)
        x, y, w, h = rect
        if w > 0 and h > 0:
            node.setPixelData(pixels, x, y, w, h)
        self._rects[node_id(node)] = rect
        document.refreshProjection()

    def _insert_below(self, document: Document, source_node: Node, node: Node) -> str:
        parent = _parent(source_node)
        siblings = parent.childNodes()
        i = _index_of(siblings, source_node)
        if i > 0:
            parent.addChildNode(node, siblings[i - 1])
            return ""
        # The source is the lowest layer of its group: Krita 5.1's scripting API adds a layer
        # above a given node or at the top, never at the bottom; put it above and say so.
        parent.addChildNode(node, source_node)
        return (
            f"'{source_node.name()}' is the lowest layer, and Krita's scripting API cannot add a layer "
            "below it: the shadow was put above it. Move the shadow layer below the cutout "
            "(or add a layer under the cutout first)."
        )


def read_annotation(document: Document, kind: str) -> bytes:
    """The document's annotation of type ``kind`` (empty when it has none)."""
    return bytes(document.annotation(kind))


def write_annotation(document: Document, kind: str, description: str, data: bytes) -> None:
    """Set (add or replace) the document's annotation of type ``kind``. Krita saves it in the .kra file; it
    touches no pixel and adds no undo step, and marks the document modified."""
    from PyQt5.QtCore import QByteArray

    document.setAnnotation(kind, description, QByteArray(data))


def horizontal_guides(document: Document | None) -> list[float]:
    """The document's horizontal guides (canvas rows), in Krita's order; none without a document."""
    return list(document.horizontalGuides()) if document is not None else []
