"""Runs inside real Krita (kritarunner): two objects on one layer, and each alone, through the plug-in's generate.

Called as ``kritarunner -s krita_objects_driver -f main`` with the installed plug-in's pykrita folder on PYTHONPATH;
$SSN_TEST_RESULT names the JSON file it writes, beside which it writes each shadow layer's alpha (uint8, W x H,
raw) as ``<layer>.alpha``.
"""

import json
import os
import traceback
from pathlib import Path
from typing import Any

from krita import Krita
from krita_driver import activate, pixel, wait_for

RESULT = Path(os.environ.get("SSN_TEST_RESULT", "/tmp/ssn_krita_objects.json"))
W, H = 640, 400
POSTS = {"A": (100, 100, 160, 340), "B": (440, 200, 470, 300)}  # x0, y0, x1, y1: a tall post and a short far one
CAMERA = {"horizon": 150.0, "fov": 45.0}


def paint(node, boxes):
    for x0, y0, x1, y1 in boxes:
        node.setPixelData(pixel("U8", (40, 90, 200), 255) * ((x1 - x0) * (y1 - y0)), x0, y0, x1 - x0, y1 - y0)


def main(*args):
    out: dict[str, Any] = {"layers": {}}
    try:
        from ssn_shadow.adapters.host import KritaHost
        from ssn_shadow.controller import ShadowController
        from ssn_shadow.engine import EngineProcess
        from ssn_shadow.shared import light_map as lm

        k = Krita.instance()
        doc = k.createDocument(W, H, "ssn-objects", "RGBA", "U8", "", 72.0)
        k.openWindow().addView(doc)  # the active layer follows a view
        root = doc.rootNode()
        layers = {"Both": list(POSTS.values()), "A": [POSTS["A"]], "B": [POSTS["B"]], "A at half": [POSTS["A"]]}
        for name, boxes in layers.items():
            node = doc.createNode(name, "paintlayer")
            paint(node, boxes)
            if name == "A at half":
                node.setOpacity(128)  # the layer's opacity, which its pixels' alpha does not carry
            root.addChildNode(node, None)
        engine = EngineProcess()
        host = KritaHost(k)
        host.active_document = lambda: doc
        controller = ShadowController(engine, host)
        messages = out["messages"] = []
        controller.model.status_changed.connect(lambda status: messages.append(list(status)))
        controller.live = False  # set as a user would before pressing Generate
        model = controller.model
        model.light_map = lm.preset("low-sun-left")
        model.horizon, model.fov, model.use_horizon = CAMERA["horizon"], CAMERA["fov"], True
        controller.live = True
        for name in layers:
            activate(doc, doc.nodeByName(name))
            controller.generate()
            wait_for(controller)
            shadow = doc.nodeByName(f"Shadow: {name}")
            out["layers"][name] = shadow is not None
            if shadow is not None:
                raw = bytes(shadow.pixelData(0, 0, W, H))
                (RESULT.parent / f"{name}.alpha").write_bytes(raw[3::4])  # BGRA: alpha last
        engine.shutdown()
        out["done"] = True
    except Exception:
        out["error"] = traceback.format_exc()
    RESULT.write_text(json.dumps(out, indent=1))
