"""Two objects on one layer inside real GIMP 3 (the chroot of test_gimp_integration), against the real worker:
each casts its own shadow, the one it casts alone, with no change to the plug-in (the engine splits the layer)."""

from __future__ import annotations

import json
import shutil
from pathlib import Path

import numpy as np
import pytest
from test_gimp_integration import BATCH_SCRIPT, run_gimp
from test_gimp_integration import chroot, worker, workdir  # noqa: F401 (its fixtures, found here by name)

pytestmark = pytest.mark.gimp

W, H = 480, 300
POSTS = {"A": [40, 40, 90, 260], "B": [330, 150, 355, 240]}  # x0, y0, x1, y1: a tall post and a short far one
ARGS = {
    "light-map": "low-sun-right",
    "opacity": 1.0,
    "ao-strength": 1.0,
    "shadow-color": [0, 0, 0],
    "use-horizon": True,
    "horizon": 100.0,
    "fov": 45.0,
}


def case(name: str, rects: list[list[int]]) -> dict:
    cutout = {"name": "Pawn", "x": 0, "y": 0, "w": W, "h": H, "rect": rects[0], "rects": rects}
    return {
        "id": name,
        "base": "RGB",
        "precision": "U8_NON_LINEAR",
        "cutout": cutout,
        "args": ARGS,
        "width": W,
        "height": H,
    }


def test_two_objects_on_one_layer_in_real_gimp(request):
    work, inner = request.getfixturevalue("workdir")
    cases = [case("both", list(POSTS.values())), *(case(name, [rect]) for name, rect in POSTS.items())]
    shutil.copy(BATCH_SCRIPT, work / "check.py")
    (work / "objects.json").write_text(json.dumps({"out_dir": inner + "/out", "cases": cases}))
    run, _ = run_gimp(inner, f'JOB_PATH = "{inner}/objects.json"; exec(open("{inner}/check.py").read())')
    results_path = work / "out" / "results.json"
    assert results_path.exists(), f"GIMP wrote no results (rc {run.returncode}):\n{(run.stdout + run.stderr)[-6000:]}"
    results = {r["name"]: r for r in json.loads(results_path.read_text())}
    shadows = {}
    for name, r in results.items():
        assert r.get("status") == "success", r
        x, y = r["shadow_offsets"]
        sw, sh = r["shadow_size"]
        pixels = np.fromfile(work / "out" / Path(r["shadow_pixels"]).name, "<f4").reshape(sh, sw, 4)[..., 3]
        canvas = np.zeros((H, W), np.float32)  # the shadow on the canvas (the layer may reach past it)
        cx0, cy0, cx1, cy1 = max(x, 0), max(y, 0), min(x + sw, W), min(y + sh, H)
        canvas[cy0:cy1, cx0:cx1] = pixels[cy0 - y : cy1 - y, cx0 - x : cx1 - x]
        shadows[name] = canvas
    for name, (x0, y0, x1, y1) in POSTS.items():
        alone = shadows[name]
        region = alone > 2 / 255
        region[y0:y1, x0:x1] = False  # the ground, not the post
        peak_alone, peak_both = np.percentile(alone[region], 95), np.percentile(shadows["both"][region], 95)
        print(f"post {name}: peak shadow alpha alone {peak_alone:.3f}, on the layer of both {peak_both:.3f}")
        assert peak_alone > 0.1
        assert peak_both == pytest.approx(peak_alone, rel=0.1), name
