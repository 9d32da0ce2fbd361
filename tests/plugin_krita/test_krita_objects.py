"""Two objects on one layer inside real Krita (kritarunner), against the real worker: each casts its own shadow,
the one it casts alone, with no change to the plug-in (the engine splits the layer); and a layer at half
opacity casts its shape's shadow half as dark."""

import sys

import numpy as np
import pytest
from krita_helpers import run_kritarunner

from plugin_krita.install import install

W, H = 640, 400
POSTS = {"A": (100, 100, 160, 340), "B": (440, 200, 470, 300)}  # as in krita_objects_driver

pytestmark = pytest.mark.krita


def test_two_objects_on_one_layer_in_real_krita(tmp_path):
    pykrita = tmp_path / "pykrita"
    install(dest=pykrita, python=sys.executable)
    data = run_kritarunner(pykrita, "krita_objects_driver", "main", tmp_path / "result.json", {})
    assert all(data["layers"].values()), data
    assert not [m for m in data["messages"] if m[0] == "error"], data["messages"]
    shadows = {name: np.fromfile(tmp_path / f"{name}.alpha", np.uint8).reshape(H, W) / 255.0 for name in data["layers"]}
    half, full = shadows["A at half"], shadows["A"]  # a layer at 50 % opacity: its shape's shadow, half as dark
    assert half.sum() / full.sum() == pytest.approx(128 / 255, abs=0.04)
    assert (half * full).sum() / np.sqrt((half**2).sum() * (full**2).sum()) > 0.99
    for name, (x0, y0, x1, y1) in POSTS.items():
        alone = shadows[name]
        region = alone > 2 / 255
        region[y0:y1, x0:x1] = False  # the ground, not the post
        peak_alone = np.percentile(alone[region], 95)
        assert peak_alone > 0.1
        assert np.percentile(shadows["Both"][region], 95) == pytest.approx(peak_alone, rel=0.1), name
