"""Two objects on one layer inside real Krita (kritarunner), against the real worker: each casts its own shadow,
the one it casts alone, with no change to the plug-in (the engine splits the layer)."""

import json
import os
import random
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest
from test_krita_integration import _need

from plugin_krita.install import install

REPO = Path(__file__).resolve().parents[2]
HERE = Path(__file__).resolve().parent
W, H = 640, 400
POSTS = {"A": (100, 100, 160, 340), "B": (440, 200, 470, 300)}  # as in krita_objects_driver

pytestmark = pytest.mark.krita


def test_two_objects_on_one_layer_in_real_krita(tmp_path):
    kritarunner, xvfb = _need("kritarunner"), _need("xvfb-run")
    pykrita = tmp_path / "pykrita"
    install(dest=pykrita, python=sys.executable)
    result = tmp_path / "result.json"
    env = dict(os.environ)
    env.update(
        SSN_TEST_RESULT=str(result),
        PYTHONPATH=os.pathsep.join([str(pykrita), str(HERE), str(REPO)]),
        XDG_RUNTIME_DIR=str(tmp_path),
    )
    env.pop("SSN_SHADOW_ENGINE_CONFIG", None)
    env["PATH"] = os.pathsep.join(["/usr/bin", "/bin", env.get("PATH", "")])  # Debian's python3 for Krita
    env.pop("QT_QPA_PLATFORM", None)
    for _attempt in range(3):  # as test_krita_integration: the display xvfb-run picks may be taken
        proc = subprocess.run(
            [xvfb, "-a", "-n", str(random.randint(200, 900)), kritarunner, "-s", "krita_objects_driver", "-f", "main"],
            env=env,
            capture_output=True,
            text=True,
            timeout=180,
        )
        if result.exists() or "could not connect to display" not in proc.stderr:
            break
    assert result.exists(), f"Krita wrote no result\n{proc.stdout[-3000:]}\n{proc.stderr[-3000:]}"
    data = json.loads(result.read_text())
    assert "error" not in data, data["error"]
    assert data["done"] and all(data["layers"].values()), data
    assert not [m for m in data["messages"] if m[0] == "error"], data["messages"]
    shadows = {name: np.fromfile(tmp_path / f"{name}.alpha", np.uint8).reshape(H, W) / 255.0 for name in data["layers"]}
    for name, (x0, y0, x1, y1) in POSTS.items():
        alone = shadows[name]
        region = alone > 2 / 255
        region[y0:y1, x0:x1] = False  # the ground, not the post
        peak_alone = np.percentile(alone[region], 95)
        assert peak_alone > 0.1
        assert np.percentile(shadows["Both"][region], 95) == pytest.approx(peak_alone, rel=0.1), name
