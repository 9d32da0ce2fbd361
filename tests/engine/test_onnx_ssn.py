"""The ONNX SSN method (ssn_engine.methods.onnx_ssn) with tiny contract-conforming models."""

from __future__ import annotations

import json
import os
import time
from pathlib import Path

import numpy as np
import pytest
from scipy import ndimage
from engine_helpers import drawn_alpha, elm_for

onnx = pytest.importorskip("onnx")
from onnx import TensorProto, helper  # noqa: E402

from ssn_engine import api  # noqa: E402
from ssn_engine.framing import frame_alpha  # noqa: E402
from ssn_engine.hemisphere import render_light_map  # noqa: E402
from ssn_engine.host_kit.light_map import GaussianLight, LightMap, preset  # noqa: E402
from ssn_engine.methods import GeometricCard, ModelError, OnnxSSN, load_method  # noqa: E402
from ssn_engine.methods.onnx_ssn import blur_frames, floor_for, reach_weights, small_lights_share  # noqa: E402

OPSET = 13


def _save(graph, path):
    model = helper.make_model(graph, opset_imports=[helper.make_opsetid("", OPSET)])
    model.ir_version = 8
    onnx.checker.check_model(model)
    onnx.save(model, str(path))


def _aop_graph(r: int, input_name: str = "mask"):
    """ao = 1 - 0.5 * mask."""
    half = helper.make_tensor("half", TensorProto.FLOAT, [], [0.5])
    one = helper.make_tensor("one", TensorProto.FLOAT, [], [1.0])
    nodes = [
        helper.make_node("Mul", [input_name, "half"], ["scaled"]),
        helper.make_node("Sub", ["one", "scaled"], ["ao"]),
    ]
    return helper.make_graph(
        nodes,
        "aop",
        [helper.make_tensor_value_info(input_name, TensorProto.FLOAT, ["b", 1, r, r])],
        [helper.make_tensor_value_info("ao", TensorProto.FLOAT, ["b", 1, r, r])],
        [half, one],
    )


def _sr_graph(r: int):
    """shadow = max(mask * peak(elm), 1 - ao): the mask wherever the ELM has light (peak 1 once normalised)."""
    one = helper.make_tensor("one", TensorProto.FLOAT, [], [1.0])
    shape = helper.make_tensor("shape", TensorProto.INT64, [4], [-1, 1, 1, 1])
    nodes = [
        helper.make_node("ReduceMax", ["elm"], ["peak3"], axes=[1, 2], keepdims=1),
        helper.make_node("Reshape", ["peak3", "shape"], ["peak"]),
        helper.make_node("Mul", ["mask", "peak"], ["lit"]),
        helper.make_node("Sub", ["one", "ao"], ["occ"]),
        helper.make_node("Max", ["lit", "occ"], ["shadow"]),
    ]
    return helper.make_graph(
        nodes,
        "sr",
        [
            helper.make_tensor_value_info("mask", TensorProto.FLOAT, ["b", 1, r, r]),
            helper.make_tensor_value_info("ao", TensorProto.FLOAT, ["b", 1, r, r]),
            helper.make_tensor_value_info("elm", TensorProto.FLOAT, ["b", 16, 32]),
        ],
        [helper.make_tensor_value_info("shadow", TensorProto.FLOAT, ["b", 1, r, r])],
        [one, shape],
    )


def _card(r: int, **extra) -> dict:
    card = {
        "format": "ssn-shadow-model",
        "version": 1,
        "resolution": r,
        "elm_shape": [16, 32],
        "aop": "aop.onnx",
        "sr": "sr.onnx",
    }
    card.update(extra)
    return card


def make_model_dir(folder, r: int = 256, card: dict | None = None, aop_input: str = "mask"):
    folder.mkdir(parents=True, exist_ok=True)
    _save(_aop_graph(r, aop_input), folder / "aop.onnx")
    _save(_sr_graph(r), folder / "sr.onnx")
    (folder / "model.json").write_text(json.dumps(card if card is not None else _card(r)))
    return folder


@pytest.fixture(scope="module")
def mask():
    m, _ = frame_alpha(drawn_alpha(160, 120), 256)
    return m


@pytest.mark.parametrize("r", [256, 128])
def test_ssn_loads_and_runs_at_any_model_resolution(tmp_path, monkeypatch, mask, r):
    folder = make_model_dir(tmp_path / f"model{r}", r)
    monkeypatch.setenv("SSN_SHADOW_MODEL_DIR", str(folder))
    for name in ("ssn", "auto"):
        loaded = load_method(name)
        assert isinstance(loaded.method, OnnxSSN) and loaded.method.name == "ssn"
        assert str(folder) in loaded.note
    method = loaded.method
    assert method.resolution == 256 and method.model_resolution == r
    masks = np.stack([mask, mask[:, ::-1]])
    ao = method.predict_ao(masks)
    assert ao.shape == (2, 256, 256) and ao.dtype == np.float32
    tol = 1e-5 if r == 256 else 0.02  # resampled through R x R when R != 256
    assert np.abs(ao - (1 - 0.5 * masks)).mean() < tol
    elms = np.stack([elm_for(0.3, 0.5), 0.001 * elm_for(0.7, 0.2)])  # any positive scale: normalised to peak 1
    s = method.render(masks, ao, elms)
    assert s.shape == (2, 256, 256) and s.dtype == np.float32
    assert 0.0 <= s.min() and s.max() <= 1.0
    assert np.abs(s - masks).mean() < tol
    if r != 256:
        assert np.abs(s - masks).max() > 1e-3  # really went through the smaller frame
    # an ELM without light gives no shadow, even where the graph would say otherwise
    dark = method.render(masks, np.zeros_like(ao), np.zeros((2, 16, 32), np.float32))
    assert not dark.any()
    # the AO input is used: no contact occlusion at all, full darkness from 1 - ao
    assert np.allclose(method.render(masks, np.zeros_like(ao), elms), 1.0)


def test_output_floor_removes_faint_values_and_keeps_full_shadow(tmp_path, monkeypatch, mask):
    plain = OnnxSSN(make_model_dir(tmp_path / "plain", 256))
    floored = OnnxSSN(make_model_dir(tmp_path / "floored", 256, _card(256, output_floor=0.1)))
    masks = np.stack([mask])
    ao = np.full_like(masks, 0.95)  # 1 - ao = 0.05: a faint everywhere-shadow below the floor
    elms = elm_for(0.5, 0.3)[None]
    s, f = plain.render(masks, ao, elms), floored.render(masks, ao, elms)
    background = masks[0] == 0
    assert np.allclose(s[0][background], 0.05, atol=1e-6) and not f[0][background].any()
    assert np.allclose(f[0][masks[0] == 1], 1.0)
    inside = (s > 0.2) & (s < 0.9)
    assert np.allclose(f[inside], (s[inside] - 0.1) / 0.9, atol=1e-6)


def test_ao_gamma_lightens_the_predicted_ao_the_renderer_gets(tmp_path, mask):
    """``ao_gamma`` calibrates the AOP's map (ao ** gamma); an AO map given to the renderer is used as it is."""
    plain = OnnxSSN(make_model_dir(tmp_path / "plain", 256))
    lighter = OnnxSSN(make_model_dir(tmp_path / "lighter", 256, _card(256, ao_gamma=0.5)))
    masks = np.stack([mask])
    ao, calibrated = plain.predict_ao(masks), lighter.predict_ao(masks)
    np.testing.assert_allclose(calibrated, ao**0.5, atol=1e-6)
    inside = masks[0] == 1.0
    assert np.allclose(ao[0][inside], 0.5, atol=1e-5) and np.allclose(calibrated[0][inside], 0.5**0.5, atol=1e-5)
    elms = elm_for(0.5, 0.3)[None]
    np.testing.assert_array_equal(lighter.render(masks, ao, elms), plain.render(masks, ao, elms))


def test_one_small_light_gets_its_own_floor_and_a_broad_sky_the_general_one(tmp_path, mask):
    """A sun's shadow is hard-edged with no faint tails, so its faint values are the network's haze: the
    small-light floor removes more of them; a broad sky's faint tails are real and keep the lower floor."""
    card = _card(256, output_floor=0.02, output_floor_small_lights=0.1)
    method = OnnxSSN(make_model_dir(tmp_path / "m", 256, card))
    masks = np.stack([mask, mask])
    ao = np.full_like(masks, 0.95)  # 1 - ao = 0.05 everywhere: between the two floors
    sky = render_light_map(preset("overcast"), 16)
    sun = render_light_map(preset("high-sun"), 16)
    s = method.render(masks, ao, np.stack([sky, sun]))
    background = masks[0] == 0
    assert np.allclose(s[0][background], (0.05 - 0.02) / 0.98, atol=1e-6)  # the sky: the general floor
    assert not s[1][background].any()  # the sun: its faint values removed
    assert np.allclose(s[:, masks[0] == 1], 1.0)  # full shadow stays full
    softbox = render_light_map(LightMap([GaussianLight(0.38, 0.45, 0.02, 2.0)]), 16)  # a broad Gaussian light
    floors = floor_for(small_lights_share(np.stack([sky, softbox, sun])), 0.02, 0.1)
    assert floors[0] == 0.02 and 0.02 < floors[1] < 0.1 and floors[2] == pytest.approx(0.1)
    assert (
        OnnxSSN(make_model_dir(tmp_path / "old", 256, _card(256, output_floor=0.03))).output_floor_small_lights == 0.03
    )


def test_predict_frames_uses_the_installed_model(tmp_path, monkeypatch, mask):
    folder = make_model_dir(tmp_path / "m", 128)
    monkeypatch.setenv("SSN_SHADOW_MODEL_DIR", str(folder))
    api.default_method.cache_clear()
    try:
        s = api.predict_frames(mask[None], elm_for(0.5, 0.5)[None])
        assert api.default_method().method.name == "ssn"
    finally:
        api.default_method.cache_clear()
    assert s.shape == (1, 256, 256) and np.abs(s[0] - mask).mean() < 0.02


def _expect_model_error(folder, monkeypatch, *fragments):
    monkeypatch.setenv("SSN_SHADOW_MODEL_DIR", str(folder))
    with pytest.raises(ModelError) as info:
        load_method("ssn")
    for fragment in fragments:
        assert fragment in str(info.value), str(info.value)
    with pytest.raises(ModelError):
        OnnxSSN(folder)
    loaded = load_method("auto")
    assert isinstance(loaded.method, GeometricCard)
    assert "geometric" in loaded.note
    for fragment in fragments:
        assert fragment in loaded.note, loaded.note
    return str(info.value)


def test_missing_graph_file(tmp_path, monkeypatch):
    folder = make_model_dir(tmp_path / "m")
    (folder / "sr.onnx").unlink()
    _expect_model_error(folder, monkeypatch, "missing", str(folder / "sr.onnx"))


def test_corrupt_graph_file(tmp_path, monkeypatch):
    folder = make_model_dir(tmp_path / "m")
    (folder / "aop.onnx").write_bytes(np.random.default_rng(0).bytes(4096))
    _expect_model_error(folder, monkeypatch, "cannot load", str(folder / "aop.onnx"))


def test_graph_with_wrong_input_names(tmp_path, monkeypatch):
    folder = make_model_dir(tmp_path / "m", aop_input="image")
    message = _expect_model_error(folder, monkeypatch, str(folder / "aop.onnx"), "contract")
    assert "image" in message and "mask" in message


@pytest.mark.parametrize("graph", ["camera", "aop_camera", "surface", "surface_second"])
def test_a_bad_optional_graph_is_named(tmp_path, monkeypatch, graph):
    """The shipped model with its camera estimator, its camera-taking AOP or either surface graph missing, or
    replaced by the plain AOP (another contract)."""
    import shutil

    folder = tmp_path / "m"
    shutil.copytree(Path(api.__file__).parent / "models", folder)
    (folder / f"{graph}.onnx").unlink()
    _expect_model_error(folder, monkeypatch, "missing", str(folder / f"{graph}.onnx"))
    shutil.copy(folder / "aop.onnx", folder / f"{graph}.onnx")
    contract = graph.removesuffix("_second")  # the second surface graph keeps the first's contract
    _expect_model_error(folder, monkeypatch, str(folder / f"{graph}.onnx"), f"{contract} contract")


def test_the_shipped_model_fits_the_wheel_budget():
    """Every graph model.json names is a shipped file, and together they stay within the 42 MB budget."""
    folder = Path(api.__file__).parent / "models"
    card = json.loads((folder / "model.json").read_text())
    names = ("aop", "sr", "aop_camera", "camera", "surface", "surface_second")
    graphs = [folder / card[k] for k in names if card.get(k)]
    assert len(graphs) == 6 and all(g.is_file() for g in graphs)
    assert sum(g.stat().st_size for g in graphs) <= 42e6


def test_graphs_named_in_the_card(tmp_path, monkeypatch, mask):
    folder = make_model_dir(tmp_path / "m", 128, card=_card(128, aop="a.onnx", sr="s.onnx"))
    monkeypatch.setenv("SSN_SHADOW_MODEL_DIR", str(folder))
    with pytest.raises(ModelError, match="a.onnx"):
        load_method("ssn")
    os.replace(folder / "aop.onnx", folder / "a.onnx")
    os.replace(folder / "sr.onnx", folder / "s.onnx")
    assert load_method("ssn").method.model_resolution == 128


@pytest.mark.parametrize(
    "card_text, fragment",
    [
        ("{not json", "cannot read"),
        (json.dumps(_card(256, format="other")), "format"),
        (json.dumps(_card(256, version=2)), "version"),
        (json.dumps(_card(256, elm_shape=[8, 16])), "elm_shape"),
        (json.dumps(_card(100)), "resolution"),
        (json.dumps(_card("256")), "resolution"),
        (json.dumps(_card(256, output_floor=0.7)), "output_floor"),
        (json.dumps(_card(256, output_floor="0.01")), "output_floor"),
        (json.dumps(_card(256, output_floor_small_lights=0.5)), "output_floor_small_lights"),
        (json.dumps(_card(256, output_floor_small_lights=True)), "output_floor_small_lights"),
        (json.dumps(_card(256, shadow_reach=-4)), "shadow_reach"),
        (json.dumps(_card(256, shadow_reach="16")), "shadow_reach"),
        (json.dumps(_card(256, ao_gamma=0)), "ao_gamma"),
        (json.dumps(_card(256, ao_gamma=False)), "ao_gamma"),
        (json.dumps(_card(256, card_blur=-1)), "card_blur"),
        (json.dumps(_card(256, card_blur="1")), "card_blur"),
        (json.dumps(_card(256, card_blur=9.0)), "card_blur"),
    ],
)
def test_wrong_model_card(tmp_path, monkeypatch, card_text, fragment):
    folder = make_model_dir(tmp_path / "m")
    (folder / "model.json").write_text(card_text)
    _expect_model_error(folder, monkeypatch, fragment, str(folder / "model.json"))


def test_no_model_card(tmp_path, monkeypatch):
    folder = make_model_dir(tmp_path / "m")
    (folder / "model.json").unlink()
    monkeypatch.setenv("SSN_SHADOW_MODEL_DIR", str(folder))
    with pytest.raises(ModelError, match="model card missing"):
        load_method("ssn")
    loaded = load_method("auto")
    assert isinstance(loaded.method, GeometricCard)
    assert str(folder / "model.json") in loaded.note and "missing" in loaded.note


def test_empty_folder_falls_back_and_geometric_on_request(tmp_path, monkeypatch):
    monkeypatch.setenv("SSN_SHADOW_MODEL_DIR", str(tmp_path))
    assert isinstance(load_method("auto").method, GeometricCard)
    assert isinstance(load_method("geometric").method, GeometricCard)
    with pytest.raises(ValueError, match="method"):
        load_method("magic")


def test_model_that_loads_but_gives_the_wrong_shape(tmp_path, monkeypatch):
    folder = make_model_dir(tmp_path / "m", 128)
    # an SR graph that answers at another size than its input
    pool = helper.make_graph(
        [helper.make_node("MaxPool", ["mask"], ["shadow"], kernel_shape=[2, 2], strides=[2, 2])],
        "sr",
        [
            helper.make_tensor_value_info("mask", TensorProto.FLOAT, ["b", 1, 128, 128]),
            helper.make_tensor_value_info("ao", TensorProto.FLOAT, ["b", 1, 128, 128]),
            helper.make_tensor_value_info("elm", TensorProto.FLOAT, ["b", 16, 32]),
        ],
        [helper.make_tensor_value_info("shadow", TensorProto.FLOAT, ["b", 1, 64, 64])],
    )
    _save(pool, folder / "sr.onnx")
    _expect_model_error(folder, monkeypatch, "shape")


def test_reach_weights_keep_the_shadow_near_the_card_and_the_cutout_only():
    """Full weight near where the card casts or the cutout stands, none far from both, falling in between."""
    card = np.zeros((1, 128, 128), np.float32)
    card[0, 60:70, 20:40] = 0.5  # where the card's shadow falls
    masks = np.zeros_like(card)
    masks[0, 20:60, 90:100] = 1.0  # the cutout
    w = reach_weights(card, masks, 8.0)[0]
    assert w.shape == (128, 128) and w.dtype == np.float32 and w.min() >= 0.0 and w.max() <= 1.0
    assert (w[58:72, 18:42] == 1.0).all() and (w[18:62, 88:102] == 1.0).all()  # 2 pixels around both
    assert w[0:5, 0:5].max() == 0.0 and w[120:, 60:80].max() == 0.0  # far from both
    row = w[65, 40:64]  # leaving the card's shadow sideways: never rising, from 1 to nothing
    assert row[0] == 1.0 and row[-1] < 0.005 and (np.diff(row) <= 1e-6).all()


def test_blur_frames_softens_the_cards_steps_and_keeps_its_shadow():
    """A blurred card keeps its amount of shadow and its place, loses its one-pixel steps; sigma 0 changes nothing."""
    card = np.zeros((2, 64, 64), np.float32)
    card[0, 30:34, 10:50] = 1.0
    card[0, 29, 10:50:2] = 1.0  # a stepped edge, as the card's wedge tips are traced
    card[1, 5:20, 40:60] = 0.5
    assert blur_frames(card, 0.0) is card
    soft = blur_frames(card, 0.8)
    assert soft.shape == card.shape and soft.dtype == np.float32
    np.testing.assert_allclose(soft.sum(axis=(1, 2)), card.sum(axis=(1, 2)), rtol=1e-4)
    assert np.abs(np.diff(soft[0, 29, 10:50])).max() < 0.5 * np.abs(np.diff(card[0, 29, 10:50])).max()
    assert soft[1, 12, 50] == pytest.approx(0.5, abs=1e-3) and soft[1, 40, 10] == 0.0  # inside, far from it


def test_the_model_holds_no_core_once_a_light_change_returns(mask):
    """onnxruntime's threads do not spin: a worker waiting for the next light change uses no CPU that the host (or
    the canvas work after the graph) needs."""
    model = OnnxSSN(Path(api.__file__).parent / "models")
    masks = mask[None]
    ao = model.predict_ao(masks)
    elm = render_light_map(preset("two-lights"))[None]
    for _ in range(5):
        model.render(masks, ao, elm)
    before = os.times()
    time.sleep(0.3)
    after = os.times()
    busy = (after.user - before.user) + (after.system - before.system)
    assert busy < 0.015, f"{busy:.3f} s of CPU in 0.3 s of idling after a render"


def test_a_mirrored_cutout_is_read_as_the_mirror_image_of_its_surface():
    """The surface model's reading is the average of its readings of the mask and of the mask mirrored left to
    right: a cutout flipped left to right stands on the mirror image of its surface, so its shadow under the
    mirrored light is the mirror image of its shadow (a lone reading of the model is not exactly so)."""
    method = load_method("ssn").method
    assert isinstance(method, OnnxSSN)
    mask = np.zeros((1, 256, 256), np.float32)
    mask[0, 70:220, 60:190] = 1.0  # a body on legs, one side longer than the other
    mask[0, 90:150, 40:60] = 1.0
    mask[0, 170:220, 100:160] = 0.0
    camera = np.array([[40.0, 300.0]])
    heights = method.pixel_heights(mask, camera)
    mirrored = method.pixel_heights(mask[..., ::-1].copy(), camera)
    assert heights is not None and mirrored is not None
    # (off the mask, and where the enlarging reaches off it, a pixel stands on its nearest covered pixel's foot, ties
    # broken one way)
    inside = ndimage.binary_erosion(mask[0] > 0, iterations=4)
    assert np.abs(mirrored - heights[..., ::-1])[0, 0][inside].max() < 0.5  # rows (a lone reading: 21 off here)


def test_the_surface_model_reads_a_post_as_standing_on_its_lowest_row(tmp_path, monkeypatch):
    """The shipped surface model's pixel heights of an upright post, camera given: each pixel's foot on (about)
    the post's lowest row, so the height falls from the post's height at its top to 0 at its foot; off the
    mask, its nearest covered pixel's foot. A model without a surface graph reads none."""
    method = load_method("ssn").method
    assert isinstance(method, OnnxSSN)
    mask = np.zeros((1, 256, 256), np.float32)
    mask[0, 60:220, 118:138] = 1.0
    camera = np.array([[40.0, 300.0]])
    heights = method.pixel_heights(mask, camera)
    assert heights is not None and heights.shape == (1, 2, 256, 256)  # the visible surface's and the far one's
    rows = np.arange(256) + 0.5
    feet = heights[0, 0, 60:220, 118:138] + rows[60:220, None]
    assert np.median(np.abs(feet - 220.0)) < 8.0  # within 5 % of the post's height
    # off the mask, a pixel stands on its nearest covered pixel's foot: the corner on the top's
    assert abs((heights[0, 0, 10, 10] + 10.5) - (heights[0, 0, 60, 118] + 60.5)) < 1.0
    monkeypatch.setenv("SSN_SHADOW_MODEL_DIR", str(make_model_dir(tmp_path / "m")))
    plain = load_method("ssn").method
    assert isinstance(plain, OnnxSSN) and plain.pixel_heights(mask, camera) is None


def test_a_part_either_surface_graph_reads_raised_stands_raised(tmp_path, monkeypatch):
    """With the shipped second surface graph, each pixel's surface stands at least as high as the first graph
    alone reads it, and higher where the second reads it higher (a body among thin legs seen at eye level, which
    one graph reads on the ground and the other raised); its depth is the first graph's."""
    import shutil

    mask = np.zeros((1, 256, 256), np.float32)
    mask[0, 90:140, 100:160] = 1.0  # a body
    for x0 in (40, 70, 170, 200):  # thin legs reaching out and down to the ground
        for i in range(60):
            mask[0, 120 + i, x0 + i // 3 : x0 + i // 3 + 4] = 1.0
    camera = np.array([[120.0, 300.0]])  # at eye level
    pair = load_method("ssn").method
    assert isinstance(pair, OnnxSSN)
    both = pair.pixel_heights(mask, camera)
    folder = tmp_path / "m"
    shutil.copytree(Path(api.__file__).parent / "models", folder)
    card = json.loads((folder / "model.json").read_text())
    del card["surface_second"]
    (folder / "model.json").write_text(json.dumps(card))
    monkeypatch.setenv("SSN_SHADOW_MODEL_DIR", str(folder))
    first = load_method("ssn").method
    assert isinstance(first, OnnxSSN)
    alone = first.pixel_heights(mask, camera)
    assert both is not None and alone is not None and both.shape == alone.shape == (1, 2, 256, 256)
    inside = ndimage.binary_erosion(mask[0] > 0, iterations=2)
    raised = (both - alone)[0, 0][inside]
    assert raised.min() > -0.5  # rows: never lower (up to the enlarging's rounding)
    assert np.percentile(raised, 90) > 2.0  # and higher over part of it
    depth = lambda h: (h[0, 0] - h[0, 1])[inside]  # noqa: E731
    assert np.abs(depth(both) - depth(alone)).max() < 0.5
