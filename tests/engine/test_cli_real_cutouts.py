"""Real cutouts through the command line: specks, fragments and half-transparent layers never wreck a shadow.

Background removal leaves specks and fringes; an eraser leaves fragments; a layer may be half transparent. A
speck too small to read casts nothing and changes neither the object's frame nor its camera; a fragment alone
still gets a shadow (its camera, read or given, is never refused); a half-transparent cutout casts its opaque
shape's shadow, as dark as it is opaque."""

from __future__ import annotations

import contextlib
import io
import json
import re

import numpy as np
import pytest
from engine_helpers import converse
from PIL import Image
from skimage import data, transform

from ssn_engine.cli import main
from ssn_engine.host_kit.light_map import preset
from ssn_engine.layer_session import open_session
from ssn_engine.methods import load_method
from ssn_engine.worker import Worker

W, H = 2000, 1500
READ = re.compile(r"camera read from the cutout's outline: --horizon (-?\d+) --fov (\d+)")


def horse() -> np.ndarray:
    """scikit-image's horse at twice its size, standing on canvas row 956 (uint8 alpha, W x H)."""
    shape = transform.resize((~data.horse()).astype(float), (656, 800), order=1) > 0.5
    alpha = np.zeros((H, W), np.uint8)
    alpha[300:956, 600:1400] = shape * 255
    return alpha


def render(tmp_path, name: str, alpha: np.ndarray, capsys, *extra: str) -> tuple[np.ndarray, str]:
    """The sun's shadow layer alpha (0..1) for a cutout, and what the CLI printed."""
    rgba = np.zeros((H, W, 4), np.uint8)
    rgba[..., :3] = (120, 90, 60)
    rgba[..., 3] = alpha
    Image.fromarray(rgba, "RGBA").save(tmp_path / f"{name}.png")
    out = tmp_path / f"{name}_layer.png"
    argv = ["render", str(tmp_path / f"{name}.png"), "--preset", "sun", "--layer", str(out), *extra]
    assert main(argv) == 0
    printed = capsys.readouterr().out
    return np.asarray(Image.open(out))[..., 3] / 255.0, printed


def cosine(a: np.ndarray, b: np.ndarray) -> float:
    return float((a * b).sum() / np.sqrt((a * a).sum() * (b * b).sum()))


@pytest.fixture(scope="module")
def opaque(tmp_path_factory) -> tuple[np.ndarray, tuple[str, ...]]:
    """The opaque horse's shadow, blind, and the camera read from its outline (horizon, fov as printed)."""
    tmp = tmp_path_factory.mktemp("opaque")
    rgba = np.zeros((H, W, 4), np.uint8)
    rgba[..., 3] = horse()
    Image.fromarray(rgba, "RGBA").save(tmp / "horse.png")
    out = tmp / "layer.png"
    with contextlib.redirect_stdout(io.StringIO()) as printed:
        assert main(["render", str(tmp / "horse.png"), "--preset", "sun", "--layer", str(out)]) == 0
    return np.asarray(Image.open(out))[..., 3] / 255.0, READ.search(printed.getvalue()).groups()


@pytest.mark.parametrize("where", [(100, 1800), (1400, 100), (960, 1900)], ids=["sky", "ground", "beside"])
def test_a_far_speck_changes_neither_the_camera_nor_the_shadow(tmp_path, capsys, opaque, where):
    plain, camera = opaque
    alpha = horse()
    y, x = where
    alpha[y : y + 4, x : x + 4] = 255
    specked, printed = render(tmp_path, "specked", alpha, capsys)
    assert READ.search(printed).groups() == camera
    assert specked.sum() == pytest.approx(plain.sum(), rel=0.01)
    assert cosine(specked, plain) > 0.999


@pytest.mark.parametrize("camera", [[], ["--horizon", "540", "--fov", "40"]], ids=["blind", "image camera"])
def test_a_fragment_alone_casts_a_shadow_and_its_camera_is_never_refused(tmp_path, capsys, camera):
    """A cutout erased down to a 17 x 5-pixel fragment on a large canvas: the image's camera (the one the whole
    horse stood under) is taken, and the camera read from the fragment can be given back as it is printed."""
    alpha = np.zeros((H, W), np.uint8)
    alpha[900:905, 1000:1017] = 255
    shadow, printed = render(tmp_path, "fragment", alpha, capsys, *camera)
    assert shadow.max() > 0.2
    if not camera:
        horizon, fov = READ.search(printed).groups()
        again, _ = render(tmp_path, "again", alpha, capsys, "--horizon", horizon, "--fov", fov)
        assert again.max() > 0.1  # the camera a sliver reads grazes its foot: its shadow is a sliver too


@pytest.mark.parametrize("level", [0.5, 0.3])
def test_a_half_transparent_cutout_casts_the_opaque_shape_as_dark_as_it_is_opaque(tmp_path, capsys, opaque, level):
    alpha = np.round(horse() * level).astype(np.uint8)
    shadow, _ = render(tmp_path, "faint", alpha, capsys)
    assert cosine(shadow, opaque[0]) > 0.99
    assert shadow.sum() / opaque[0].sum() == pytest.approx(level, abs=0.03)


def test_a_layers_opacity_the_alpha_does_not_carry_scales_its_shadow():
    """A host sends a layer's opacity beside its alpha (``set_cutout``'s ``layer_opacity``): a horse on a 50 %
    layer casts the opaque horse's shadow at half its darkness; a value outside 0 to 1 is refused by name."""
    method = load_method("auto").method
    sun = preset("sun")
    full, half = (open_session(horse(), method, layer_opacity=o).render(sun).full_canvas(W, H) for o in (1.0, 0.5))
    assert half.sum() / full.sum() == pytest.approx(0.5, abs=0.02) and cosine(half, full) > 0.999
    worker = Worker(load_method("geometric"))
    alpha = horse()
    entry = {"name": "alpha", "dtype": "uint8", "shape": list(alpha.shape), "nbytes": alpha.size}
    request = {"id": 1, "cmd": "set_cutout", "layer_opacity": 1.5, "buffers": [entry]}
    reply = converse(worker, json.dumps(request).encode() + b"\n" + alpha.tobytes())[0][0]
    assert reply["error"]["type"] == "BadRequest" and "layer_opacity: expected" in reply["error"]["message"]
