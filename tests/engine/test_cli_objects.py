"""Several objects on one layer through the command line: each casts the shadow it casts alone."""

from __future__ import annotations

import re

import numpy as np
import pytest
from engine_helpers import pawn_scene, peak_alpha
from PIL import Image

from ssn_engine.cli import main

W, H = 1000, 640
SCENES = {
    "two": [(400, 590, 240), (220, 500, 740)],
    "three": [(380, 600, 190), (240, 520, 540), (150, 450, 850)],
}


def cutout(path, alpha: np.ndarray):
    rgba = np.zeros((H, W, 4), np.uint8)
    rgba[..., :3] = (200, 110, 60)
    rgba[..., 3] = alpha
    Image.fromarray(rgba, "RGBA").save(path)
    return str(path)


def layer_alpha(tmp_path, name: str, alpha: np.ndarray, camera: list[str], capsys) -> tuple[np.ndarray, str]:
    """The shadow layer's alpha (0..1) the CLI renders for a cutout, and what it printed."""
    out = tmp_path / f"{name}_layer.png"
    argv = ["render", cutout(tmp_path / f"{name}.png", alpha), "--preset", "low-sun-left", "--layer", str(out)]
    assert main([*argv, *camera]) == 0
    return np.asarray(Image.open(out))[..., 3] / 255.0, capsys.readouterr().out


@pytest.mark.parametrize("scene", SCENES)
@pytest.mark.parametrize("blind", [False, True], ids=["camera", "blind"])
def test_each_object_on_a_layer_casts_its_own_shadow(tmp_path, capsys, scene, blind):
    alphas = pawn_scene(W, H, SCENES[scene])
    camera = [] if blind else ["--horizon", "300", "--fov", "45"]
    together, printed = layer_alpha(tmp_path, "layer", np.maximum.reduce(alphas), camera, capsys)
    if blind:  # one camera read for the image: each object alone is rendered with it
        read = re.search(r"camera read from the cutout's outline: (--horizon -?\d+ --fov \d+)", printed)
        assert read, printed
        camera = read.group(1).split()
    for i, alpha in enumerate(alphas):
        alone, _ = layer_alpha(tmp_path, f"alone{i}", alpha, camera, capsys)
        region = (alone > 2 / 255) & (alpha < 3)
        assert peak_alpha(alone, region) > 0.1
        assert peak_alpha(together, region) == pytest.approx(peak_alpha(alone, region), rel=0.1), f"object {i}"


def test_one_object_still_stands_each_part_on_its_own_ground(tmp_path, capsys):
    """--one-object frames the whole alpha as one cutout; under the sun its shadow is traced standing on the
    cutout's contact line, which rises to the far pawn's foot: the far pawn casts the shadow it casts alone, not
    the faint one of a part floating above the near pawn's foot."""
    alphas = pawn_scene(W, H, SCENES["two"])
    camera = ["--horizon", "300", "--fov", "45"]
    layer = np.maximum.reduce(alphas)
    one, _ = layer_alpha(tmp_path, "one", layer, [*camera, "--one-object"], capsys)
    alone, _ = layer_alpha(tmp_path, "alone", alphas[1], camera, capsys)
    region = (alone > 2 / 255) & (alphas[1] < 3)
    assert peak_alpha(one, region) == pytest.approx(peak_alpha(alone, region), rel=0.1)
