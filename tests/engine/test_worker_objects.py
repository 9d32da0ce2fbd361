"""Several objects on one layer through the worker's requests, as the hosts send them (in-process)."""

from __future__ import annotations

import numpy as np
import pytest
from engine_helpers import pawn_scene, peak_alpha

from ssn_engine.framing import frame_alpha
from ssn_engine.methods import load_method
from ssn_engine.worker import Worker, to_array, to_buffer

W, H = 1000, 640
PAWNS = [(400, 590, 240), (220, 500, 740)]


@pytest.fixture(scope="module")
def worker() -> Worker:
    return Worker(load_method("auto"))


def ask(worker: Worker, header: dict, **buffers: np.ndarray) -> tuple[dict, dict]:
    reply, out = worker.handle(header, {k: to_buffer(v) for k, v in buffers.items()})
    assert reply["ok"], reply
    return reply, {k: to_array(v) for k, v in out.items()}


def layer_alpha(worker: Worker, alpha: np.ndarray, **render) -> np.ndarray:
    """The rendered layer's alpha (0..1) on the canvas, for a new cutout of ``alpha``."""
    reply, _ = ask(worker, {"cmd": "set_cutout", "camera": {"horizon": 300, "fov": 45}}, alpha=alpha)
    rendered, out = ask(worker, {"cmd": "render", "cutout": reply["cutout"], "preset": "low-sun-left", **render})
    canvas = np.zeros((H, W))
    x, y, w, h = (rendered[k] for k in ("x", "y", "width", "height"))
    canvas[y : y + h, x : x + w] = out["layer"][..., 3] / 255.0
    return canvas


def test_a_layer_of_two_objects_through_the_worker(worker):
    alphas = pawn_scene(W, H, PAWNS)
    layer = np.maximum.reduce(alphas)
    together = layer_alpha(worker, layer)
    for alpha in alphas:
        alone = layer_alpha(worker, alpha)
        region = (alone > 2 / 255) & (alpha < 3)
        assert peak_alpha(together, region) == pytest.approx(peak_alpha(alone, region), rel=0.1)


def test_ao_and_a_preview_of_a_two_object_layer(worker):
    layer = np.maximum.reduce(pawn_scene(W, H, PAWNS))
    reply, _ = ask(worker, {"cmd": "set_cutout"}, alpha=layer)
    key = reply["cutout"]
    assert reply["camera_read"]["fov"] > 0  # blind: the camera read for the image
    x0, y0, x1, y1 = reply["bbox"]  # the whole layer's box
    assert x0 < 240 - 100 and x1 > 740 + 50 and y1 >= 590
    _, ao = ask(worker, {"cmd": "get_ao", "cutout": key})
    assert ao["ao"].shape == ao["mask"].shape == (256, 256) and ao["ao"].min() < 150  # contacts darkened
    x, y = frame_alpha(layer)[1].to_frame(240, 590)  # the big pawn's foot on the layer's frame, as get_ao shows it
    dab = {"op": "brush", "x": x / 256, "y": y / 256, "radius": 0.05, "strength": -1.0}
    _, edited = ask(worker, {"cmd": "edit_ao", "cutout": key, "edits": [dab]})
    assert edited["ao"].shape == (256, 256) and edited["ao"][int(y), int(x)] < ao["ao"][int(y), int(x)] - 20
    background = np.full((H // 4, W // 4, 3), 200, np.uint8)
    _, preview = ask(
        worker, {"cmd": "preview", "cutout": key, "preset": "low-sun-left", "read_horizon": True}, background=background
    )
    image = preview["image"]
    assert image.shape == (H // 4, W // 4, 3)
    for _, base, centre in PAWNS:  # the ground beside each pawn's foot is shaded
        foot = image[base // 4 - 3 : base // 4 + 2, centre // 4 - 40 : centre // 4 + 40]
        assert foot.min() < 150
