"""The cutout read again (``refresh_source``) on stand-ins for Krita's document and layer: the same source where its
alpha is unchanged, a new one (a new key) where its pixels changed. No Krita needed."""

import struct

import pytest

from plugin_krita.ssn_shadow import worker_requests
from plugin_krita.ssn_shadow.adapters.krita_document import SourceError, read_source, refresh_source

W, H = 40, 30


class Rect:
    def __init__(self, x, y, w, h):
        self._r = (x, y, w, h)

    def x(self):
        return self._r[0]

    def y(self):
        return self._r[1]

    def width(self):
        return self._r[2]

    def height(self):
        return self._r[3]


class Uid:
    def toString(self):  # noqa: N802 (Qt's name)
        return "{person}"


class Group:
    """The group a layer lies in, itself in the image's root (whose parent is None)."""

    def __init__(self, opacity=255):
        self.level = opacity

    def opacity(self):
        return self.level

    def parentNode(self):  # noqa: N802
        return Root()


class Root:
    def parentNode(self):  # noqa: N802
        return None


class Layer:
    """A paint layer of ``depth`` whose pixels are a dict (x, y) -> alpha in 0..1 (colour black)."""

    def __init__(self, depth="U8", alpha=None, parent=True, opacity=255, group_opacity=255):
        self.depth, self.alpha, self.parent = depth, dict(alpha or {}), parent
        self.reads, self.level, self.group = 0, opacity, Group(group_opacity)

    def name(self):
        return "Person"

    def uniqueId(self):  # noqa: N802
        return Uid()

    def parentNode(self):  # noqa: N802
        return self.group if self.parent else None

    def opacity(self):
        return self.level

    def colorModel(self):  # noqa: N802
        return "RGBA"

    def colorDepth(self):  # noqa: N802
        return self.depth

    def bounds(self):
        if not self.alpha:
            return Rect(0, 0, 0, 0)
        xs, ys = [x for x, _ in self.alpha], [y for _, y in self.alpha]
        return Rect(min(xs), min(ys), max(xs) - min(xs) + 1, max(ys) - min(ys) + 1)

    def projectionPixelData(self, x, y, w, h):  # noqa: N802
        self.reads += 1
        out = bytearray()
        for yy in range(y, y + h):
            for xx in range(x, x + w):
                a = self.alpha.get((xx, yy), 0.0)
                if self.depth == "U8":
                    out += bytes([0, 0, 0, round(255 * a)])
                else:
                    out += struct.pack("<4f", 0.0, 0.0, 0.0, a)
        return bytes(out)


class Selection:
    def __init__(self, box):
        self.box = box  # x0, y0, x1, y1 selected

    def width(self):
        return self.box[2] - self.box[0]

    def height(self):
        return self.box[3] - self.box[1]

    def pixelData(self, x, y, w, h):  # noqa: N802
        x0, y0, x1, y1 = self.box
        return bytes(255 if x0 <= i % w < x1 and y0 <= i // w < y1 else 0 for i in range(w * h))


class Document:
    def __init__(self, layer, selection=None):
        self.layer, self.sel = layer, selection

    def colorModel(self):  # noqa: N802
        return "RGBA"

    def colorDepth(self):  # noqa: N802
        return self.layer.depth

    def colorProfile(self):  # noqa: N802
        return "sRGB-elle-V2-srgbtrc.icc"

    def activeNode(self):  # noqa: N802
        return self.layer

    def width(self):
        return W

    def height(self):
        return H

    def selection(self):
        return self.sel


def box(x0, y0, x1, y1, a=1.0):
    return {(x, y): a for x in range(x0, x1) for y in range(y0, y1)}


@pytest.mark.parametrize("depth", ["U8", "F32"])
def test_an_unchanged_cutout_is_the_same_source_and_a_changed_one_a_new_key(depth):
    layer = Layer(depth, box(10, 5, 20, 25))
    doc = Document(layer)
    source = read_source(doc)
    key = source.key
    assert refresh_source(source) is source  # the same pixels: the same object, its key not hashed again

    erased = {p: a for p, a in layer.alpha.items() if p[0] < 15}  # the right half erased: other bounds
    layer.alpha = erased
    half = refresh_source(source)
    assert half is not source and half.key != key and half.region == (10, 5, 5, 20)
    assert refresh_source(half) is half

    layer.alpha = {**erased, (12, 10): 0.5, (11, 6): 0.25}  # alpha painted within the same bounds
    painted = refresh_source(half)
    assert painted is not half and painted.key != half.key and painted.region == half.region
    assert read_source(doc).alpha == painted.alpha  # what a Generate would read


def test_the_layers_opacity_and_its_groups_go_with_the_cutout_and_a_change_of_it_is_a_new_source():
    """The alpha does not carry the layer's opacity: a layer at 50 % in a group at 80 % shows at 40 %, sent as
    the cutout's ``layer_opacity``; an opacity changed since is a new source (a new key), a selection's is 1."""
    layer = Layer("U8", box(10, 5, 20, 25), opacity=128, group_opacity=204)
    source = read_source(Document(layer))
    assert source.opacity == pytest.approx(128 / 255 * 204 / 255)
    params, _ = worker_requests.set_cutout(source, None)
    assert params == {"layer_opacity": source.opacity}
    layer.level = layer.group.level = 255
    opaque = refresh_source(source)
    assert opaque is not source and opaque.key != source.key and opaque.alpha == source.alpha
    assert "layer_opacity" not in worker_requests.set_cutout(opaque, None)[0]
    selected = read_source(Document(layer, Selection((10, 5, 20, 25))))
    assert selected.from_selection and selected.opacity == 1.0


def test_the_layer_alpha_is_compared_within_its_region_of_a_wide_layer():
    """A layer spanning the canvas's width is compared in one piece; one pixel's change is seen."""
    layer = Layer("U8", {**box(0, 5, W, 10), (3, 20): 1.0})
    source = read_source(Document(layer))
    assert refresh_source(source) is source
    layer.alpha[(3, 20)] = 0.9
    assert refresh_source(source) is not source


def test_a_selection_source_reads_the_selection_again_and_keeps_itself_once_deselected():
    layer = Layer("U8", box(0, 0, W, H))  # opaque everywhere: the selection is the cutout
    doc = Document(layer, Selection((10, 5, 20, 25)))
    source = read_source(doc)
    assert source.from_selection and refresh_source(source) is source
    doc.sel = Selection((10, 5, 15, 25))
    smaller = refresh_source(source)
    assert smaller is not source and smaller.key != source.key and smaller.from_selection
    doc.sel = None  # deselected after Generate: the cutout is the selection that was
    assert refresh_source(smaller) is smaller


def test_a_layer_gone_keeps_the_source_and_an_emptied_one_says_so():
    layer = Layer("U8", box(10, 5, 20, 25))
    source = read_source(Document(layer))
    layer.parent = False  # removed from the image
    assert refresh_source(source) is source
    layer.parent, layer.alpha = True, {}
    with pytest.raises(SourceError, match="empty on the canvas"):
        refresh_source(source)


# -- the read skipped while Krita's undo history stands still (KritaHost, HistoryStamp) --------------------------


@pytest.fixture
def history(qapp):
    """A main window with an Undo History docker whose list's model a test appends to: a new undo command."""
    from PyQt5.QtGui import QStandardItem, QStandardItemModel
    from PyQt5.QtWidgets import QDockWidget, QListView, QMainWindow

    from plugin_krita.ssn_shadow.adapters.host import HISTORY_DOCKER

    window, dock, view, model = QMainWindow(), QDockWidget(), QListView(), QStandardItemModel()
    dock.setObjectName(HISTORY_DOCKER)
    view.setModel(model)
    dock.setWidget(view)
    window.addDockWidget(1, dock)  # Qt.LeftDockWidgetArea; hidden: Krita's hidden dockers follow the stack too
    KritaStandIn.window = window
    yield lambda name: model.appendRow(QStandardItem(name))
    KritaStandIn.window = None
    window.deleteLater()


class KritaStandIn:
    """Krita's active window (None: none), the one main window a test made."""

    window = None

    def activeWindow(self):  # noqa: N802
        window = self.window
        return None if window is None else type("Window", (), {"qwindow": lambda _: window})()


class Doc(Document):
    def setActiveNode(self, node):  # noqa: N802
        pass


def krita_host(monkeypatch, shots):
    from plugin_krita.ssn_shadow.adapters import host as host_module

    def thumbnail(document, side):
        shots.append(side)
        return 1, 1, bytes(4)

    monkeypatch.setattr(host_module, "projection_thumbnail", thumbnail)
    monkeypatch.setattr(host_module, "preview_background", lambda document, node, side: thumbnail(document, side))
    return host_module.KritaHost(KritaStandIn())  # type: ignore[arg-type]


def test_the_cutout_is_not_read_again_until_krita_records_an_undoable_change(history, monkeypatch):
    host = krita_host(monkeypatch, [])
    layer = Layer("F32", box(10, 5, 20, 25))
    source = host.read_source(Doc(layer))
    reads = layer.reads
    assert host.refresh_source(source) is source and layer.reads == reads  # nothing recorded since: no read
    layer.alpha = box(10, 5, 15, 25)  # the right half erased (a stroke: its undo command follows)
    history("Erase")
    erased = host.refresh_source(source)
    assert layer.reads == reads + 1 and erased is not source and erased.region == (10, 5, 5, 20)
    assert host.refresh_source(erased) is erased and layer.reads == reads + 1
    history("Undo")  # any change of the history reads it again, even one that leaves the pixels as they were
    assert host.refresh_source(erased) is erased and layer.reads == reads + 2


def test_without_a_window_the_cutout_is_read_at_each_edit(qapp, monkeypatch):
    host = krita_host(monkeypatch, [])
    layer = Layer("U8", box(10, 5, 20, 25))
    source = host.read_source(Doc(layer))
    reads = layer.reads
    assert host.refresh_source(source) is source and host.refresh_source(source) is source
    assert layer.reads == reads + 2


def test_the_plugins_own_layer_commands_keep_the_cutout_and_the_preview_background(history, monkeypatch):
    from plugin_krita.ssn_shadow.adapters.krita_document import WriteResult

    shots: list[int] = []
    host = krita_host(monkeypatch, shots)

    def take_over(document, node, while_out):  # a layer removed, its copy added: two undo commands
        history("Remove Layer")
        while_out()
        history("Add Layer")
        return WriteResult("copy", True, "", "copy")

    def write(document, node, pixels, rect, new_step, blend):
        history("Add Layer")
        return WriteResult("shadow", True, "", "shadow")

    monkeypatch.setattr(host.writer, "take_over", take_over)
    monkeypatch.setattr(host.writer, "write", write)
    layer = Layer("F32", box(10, 5, 20, 25))
    source = host.read_source(Doc(layer))
    host.write(source, b"", (0, 0, 0, 0), True, "normal")  # Generate's layer
    host.preview_background(source, 160)  # the preview after it
    reads = layer.reads
    for _ in range(2):  # two drags: the cutout not read again, the image without its shadow kept
        assert host.refresh_source(source) is source
        assert host.begin_drag(source, 160)[0] == (1, 1, bytes(4))
    assert layer.reads == reads and shots == [160]
    host.begin_drag(source, 120)  # the preview drawn smaller: taken again
    history("Brush stroke")  # the image painted on: both taken again
    host.refresh_source(source)
    host.begin_drag(source, 120)
    assert layer.reads == reads + 1 and shots == [160, 120, 120]


def test_another_active_window_reads_the_cutout_again(history, monkeypatch):
    from PyQt5.QtWidgets import QMainWindow

    host = krita_host(monkeypatch, [])
    layer = Layer("U8", box(10, 5, 20, 25))
    source = host.read_source(Doc(layer))
    reads, first = layer.reads, KritaStandIn.window
    KritaStandIn.window = other = QMainWindow()  # no Undo History docker: nothing to go by
    assert host.refresh_source(source) is source and host.refresh_source(source) is source
    assert layer.reads == reads + 2
    KritaStandIn.window = first  # back: it was read meanwhile, under another window's stamp
    assert host.refresh_source(source) is source and layer.reads == reads + 3
    assert host.refresh_source(source) is source and layer.reads == reads + 3
    other.deleteLater()
