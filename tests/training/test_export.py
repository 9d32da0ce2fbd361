"""ONNX export to the engine's contract, parity with torch, and loading by the engine."""

from __future__ import annotations

import json

import numpy as np
import pytest

torch = pytest.importorskip("torch")
pytest.importorskip("onnx")
ort = pytest.importorskip("onnxruntime")

from test_train_standin import FakeStore, tiny_run_args  # noqa: E402

from training.export import main as export_main  # noqa: E402
from training.train import main as train_main  # noqa: E402

TINY = tiny_run_args(32, 1, "--steps", "2")


def export(aop: list, sr, out, data, *extra: str) -> int:
    """Run `training.export` on AOP checkpoints or a graph (``aop``) and an SR checkpoint."""
    return export_main(["--aop", *map(str, aop), "--sr", str(sr), "--out", str(out), "--data", str(data), *extra])


@pytest.fixture(scope="module")
def exported(tmp_path_factory):
    tmp = tmp_path_factory.mktemp("export")
    for module in ("aop", "sr"):
        assert train_main(["--module", module, "--run", str(tmp / module), *TINY], store=FakeStore(res=32)) == 0
    out = tmp / "model"
    options = ("--floor", "0.01", "--ao-gamma", "0.6")
    assert export([tmp / "aop" / "last.pt"], tmp / "sr" / "last.pt", out, tmp / "no-data", *options) == 0
    return out


def test_contract_names_shapes_and_card(exported):
    card = json.loads((exported / "model.json").read_text())
    assert card["format"] == "ssn-shadow-model" and card["version"] == 1
    assert card["resolution"] == 32 and card["elm_shape"] == [16, 32]
    aop = ort.InferenceSession(str(exported / "aop.onnx"), providers=["CPUExecutionProvider"])
    sr = ort.InferenceSession(str(exported / "sr.onnx"), providers=["CPUExecutionProvider"])
    assert [i.name for i in aop.get_inputs()] == ["mask"] and [o.name for o in aop.get_outputs()] == ["ao"]
    assert [i.name for i in sr.get_inputs()] == ["mask", "ao", "elm"]
    assert [o.name for o in sr.get_outputs()] == ["shadow"]
    for batch in (1, 3):
        m = np.random.default_rng(batch).random((batch, 1, 32, 32), dtype=np.float32)
        ao = aop.run(None, {"mask": m})[0]
        s = sr.run(None, {"mask": m, "ao": ao, "elm": np.ones((batch, 16, 32), np.float32)})[0]
        assert ao.shape == s.shape == (batch, 1, 32, 32)
        assert 0 <= s.min() and s.max() <= 1 and 0 <= ao.min() and ao.max() <= 1


def test_parity_is_recorded_and_within_bound(exported):
    report = json.loads((exported / "model.json").read_text())["export"]
    for module in ("aop", "sr"):
        assert report[module]["max_abs_diff"] <= 1e-4
        assert report[module]["weights"] == "float32"
    assert report["timing"]["sr_at_R_ms"] > 0
    card = (exported / "MODEL_CARD.md").read_text()
    assert "# SSN shadow model" in card and "Output floor 0.01" in card and "AO gamma 0.6" in card


def test_the_engine_loads_the_export(exported):
    from ssn_engine.methods.onnx_ssn import OnnxSSN

    method = OnnxSSN(exported)
    assert method.output_floor == 0.01  # export --floor reaches the engine through model.json
    assert method.ao_gamma == 0.6  # and --ao-gamma
    masks = np.zeros((2, 256, 256), np.float32)
    masks[:, 60:200, 100:150] = 1
    ao = method.predict_ao(masks)
    s = method.render(masks, ao, np.ones((2, 16, 32), np.float32))
    assert s.shape == (2, 256, 256) and s.dtype == np.float32


def test_fixed_group_norm_is_group_norm():
    from training.onnx_graphs import FixedGroupNorm

    gn = torch.nn.GroupNorm(4, 8)
    with torch.no_grad():
        gn.weight.uniform_(0.5, 2)
        gn.bias.uniform_(-1, 1)
    x = torch.randn(3, 8, 16, 12) * 5 + 2
    torch.testing.assert_close(FixedGroupNorm(gn, (8, 16, 12))(x), gn(x), atol=2e-5, rtol=1e-5)


def _sr_mirror_gap(model_dir) -> float:
    """Largest difference between SR on mirrored inputs and SR's output mirrored."""
    sr = ort.InferenceSession(str(model_dir / "sr.onnx"), providers=["CPUExecutionProvider"])
    rng = np.random.default_rng(0)
    x = {
        "mask": rng.random((2, 1, 32, 32), dtype=np.float32),
        "ao": rng.random((2, 1, 32, 32), dtype=np.float32),
        "elm": rng.random((2, 16, 32), dtype=np.float32),
    }
    direct = sr.run(None, x)[0]
    mirrored = sr.run(None, {k: np.ascontiguousarray(v[..., ::-1]) for k, v in x.items()})[0]
    return float(np.abs(mirrored[..., ::-1] - direct).max())


def test_mirror_averaged_export_is_mirror_symmetric(exported):
    out = exported.parent / "mirrored"
    runs = exported.parent
    assert export([runs / "aop" / "last.pt"], runs / "sr" / "last.pt", out, runs / "no-data", "--mirror-average") == 0
    card = json.loads((out / "model.json").read_text())
    assert card["mirror_average"] is True and card["export"]["sr"]["max_abs_diff"] <= 1e-4
    assert "- Mirror average: each graph runs its network" in (out / "MODEL_CARD.md").read_text()
    assert _sr_mirror_gap(exported) > 1e-3  # the plain network is not symmetric ...
    assert _sr_mirror_gap(out) < 1e-5  # ... its mirror average is


def test_a_mirror_averaged_aop_graph_is_reused_without_its_mirror_average(exported):
    import onnx

    from training.checkpoint import load_model

    runs = exported.parent
    mirrored, plain = runs / "aop-mirrored", runs / "aop-plain"
    aop, sr = runs / "aop" / "last.pt", runs / "sr" / "last.pt"
    assert export([aop], sr, mirrored, runs / "no-data", "--mirror-average") == 0
    assert export([mirrored / "aop.onnx"], sr, plain, runs / "no-data", "--aop-without-mirror") == 0
    m = np.random.default_rng(4).random((2, 1, 32, 32), dtype=np.float32)
    run = lambda d: ort.InferenceSession(str(d / "aop.onnx"), providers=["CPUExecutionProvider"]).run(
        None, {"mask": m}
    )[0]  # noqa: E731
    with torch.no_grad():
        net = np.clip(load_model(aop)[0](torch.from_numpy(m)).numpy(), 0, 1)
    assert np.abs(run(mirrored) - net).max() > 1e-3  # the mirror average differs from one pass ...
    assert np.abs(run(plain) - net).max() < 1e-5  # ... and the rewritten graph is that one pass
    doubling = lambda d: [
        n for n in onnx.load(str(d / "aop.onnx")).graph.node if n.op_type == "Concat" and n.input[0] == "mask"
    ]  # noqa: E731
    assert len(doubling(mirrored)) == 1 and not doubling(plain)  # no second pass on the mirror image
    assert "reused without its mirror average" in (plain / "MODEL_CARD.md").read_text()
    with pytest.raises(SystemExit):  # checkpoints have no mirror average to drop
        export([aop], sr, runs / "bad", runs / "no-data", "--aop-without-mirror")
    with pytest.raises(ValueError, match="not a mirror-averaged graph"):
        export([plain / "aop.onnx"], sr, runs / "twice", runs / "no-data", "--aop-without-mirror")


def test_two_aops_export_as_one_graph_of_their_mean(exported):
    from training.checkpoint import load, load_model

    checkpoint_widths = lambda p: load(p)["unet"]["widths"]  # noqa: E731
    runs = exported.parent
    assert (
        train_main(["--module", "aop", "--run", str(runs / "aop2"), *TINY, "--seed", "1"], store=FakeStore(res=32)) == 0
    )
    members = [runs / "aop" / "last.pt", runs / "aop2" / "last.pt"]
    out = runs / "ensemble"
    assert export(members, runs / "sr" / "last.pt", out, runs / "no-data") == 0
    m = np.random.default_rng(3).random((2, 1, 32, 32), dtype=np.float32)
    got = ort.InferenceSession(str(out / "aop.onnx"), providers=["CPUExecutionProvider"]).run(None, {"mask": m})[0]
    with torch.no_grad():
        a, b = (load_model(p)[0](torch.from_numpy(m)).numpy() for p in members)
    assert np.abs(a - b).max() > 1e-3  # two different networks ...
    assert np.abs(got - np.clip(0.5 * (a + b), 0, 1)).max() < 1e-4  # ... and the graph is their mean
    report = json.loads((out / "model.json").read_text())["export"]["aop"]
    assert report["checkpoints"] == list(map(str, members)) and report["max_abs_diff"] <= 1e-4
    assert report["widths"] == [checkpoint_widths(p) for p in members]  # each member's own U-Net
    assert "the mean of 2 networks" in (out / "MODEL_CARD.md").read_text()


def test_geometry_guided_sr_exports_with_the_card_input_and_the_engine_feeds_it(exported, tmp_path):
    """A --card SR ships beside a reused AOP graph; the engine traces the card (with the camera when given) and
    blurs it as the SR was trained (train --card-blur)."""
    from ssn_engine.methods import OnnxSSN

    run = tmp_path / "sr_card"
    assert (
        train_main(
            ["--module", "sr", "--card", "--lights", "mix", "--card-blur", "1.0", "--run", str(run), *TINY],
            store=FakeStore(res=32),
        )
        == 0
    )
    out = tmp_path / "model"
    assert export([exported / "aop.onnx"], run / "last.pt", out, tmp_path / "no-data") == 0  # blur as trained
    card = json.loads((out / "model.json").read_text())
    assert card["card_blur"] == 1.0 and "Card blur 1.0" in (out / "MODEL_CARD.md").read_text()
    assert card["export"]["sr"]["max_abs_diff"] <= 1e-4
    assert card["export"]["aop"]["reused_from"] == str(exported / "aop.onnx")
    sr_inputs = {i.name for i in ort.InferenceSession(str(out / "sr.onnx")).get_inputs()}
    assert sr_inputs == {"mask", "ao", "elm", "card"}
    method = OnnxSSN(out)
    assert method.card is not None and method.card.internal == 32 and method.card_blur == 1.0
    mask = np.zeros((1, 256, 256), np.float32)
    mask[0, 8:136, 100:156] = 1.0
    elm = np.zeros((1, 16, 32), np.float32)
    elm[0, 13, 4] = 1.0  # a low light behind the camera, to the left
    ao = method.predict_ao(mask)
    blind = method.render(mask, ao, elm)
    seen = method.render(mask, ao, elm, np.array([[-300.0, 300.0]]))
    assert blind.shape == (1, 256, 256) and 0 <= blind.min() and blind.max() <= 1
    assert np.abs(blind - seen).max() > 0.05  # the camera input reaches the network through the card


def test_a_checkpoint_rebuilt_from_the_graph_fine_tunes(exported, tmp_path):
    """`training.onnx_weights`: an exported network's weights come back as a checkpoint that reproduces the graph
    and that `training.train --init-from` starts from; a wrong U-Net is refused with a message."""
    from training import checkpoint
    from training.onnx_weights import main as rebuild_main

    out = tmp_path / "rebuilt.pt"
    assert rebuild_main([str(exported / "sr.onnx"), "--out", str(out), "--groups", "2"]) == 0
    ck = checkpoint.load(out)
    assert ck["parity"] <= 1e-4 and ck["unet"] == {
        "widths": [4, 8, 8],
        "groups": 2,
        "resolution": 32,
        "card": False,
        "camera": False,
        "outputs": 1,
    }
    run = tmp_path / "finetune"
    args = ["--module", "sr", "--run", str(run), *TINY, "--init-from", str(out)]
    assert train_main(args, store=FakeStore(res=32)) == 0
    with pytest.raises(SystemExit, match="off the graph"):
        rebuild_main([str(exported / "sr.onnx"), "--out", str(tmp_path / "bad.pt"), "--groups", "1"])
    assert rebuild_main([str(exported / "aop.onnx"), "--out", str(tmp_path / "aop.pt"), "--groups", "2"]) == 0
    assert checkpoint.load(tmp_path / "aop.pt")["module"] == "aop"
    aop_run = ["--module", "aop", "--run", str(tmp_path / "aop_ft"), *TINY, "--init-from", str(tmp_path / "aop.pt")]
    assert train_main(aop_run, store=FakeStore(res=32)) == 0  # an AOP fine-tunes from its graph too


def test_a_graph_is_reexported_as_the_same_function_without_shape_arithmetic(exported, tmp_path):
    """`training.onnx_weights --reexport`: a graph comes back as the same function in the exporter's current form,
    whose GroupNorms are fused normalisations of shapes fixed at export (no shape arithmetic to run); the shipped
    graphs are in that form; a wrong U-Net is refused with a message."""
    import onnx
    from training.onnx_weights import main as rebuild_main

    from ssn_engine.methods import MODEL_DIR as models

    for graph in ("sr.onnx", "aop.onnx"):
        out = tmp_path / graph
        assert rebuild_main([str(exported / graph), "--reexport", str(out), "--groups", "2"]) == 0
        feeds = {"mask": np.random.default_rng(0).random((3, 1, 32, 32), dtype=np.float32)}
        if graph == "sr.onnx":
            feeds |= {"ao": feeds["mask"][::-1].copy(), "elm": np.ones((3, 16, 32), np.float32)}
        old, new = (ort.InferenceSession(str(p), providers=["CPUExecutionProvider"]) for p in (exported / graph, out))
        np.testing.assert_allclose(new.run(None, feeds)[0], old.run(None, feeds)[0], atol=1e-5)
    for graph in (tmp_path / "sr.onnx", tmp_path / "aop.onnx", models / "sr.onnx", models / "aop.onnx"):
        g = onnx.load(str(graph)).graph
        fixed = {i.name for i in g.initializer} | {o for n in g.node if n.op_type == "Constant" for o in n.output}
        layer_norms = [n for n in g.node if n.op_type == "LayerNormalization"]
        normalised = {n.input[0] for n in layer_norms}
        norms = [n for n in g.node if n.op_type == "Reshape" and n.output[0] in normalised]
        assert norms and all(n.input[1] in fixed for n in norms), graph
        assert not any(n.op_type == "ReduceMean" for n in g.node), graph  # one fused kernel per GroupNorm
        filled = {n.output[0] for n in g.node if n.op_type == "ConstantOfShape"}
        assert all(len(n.input) == 2 and n.input[1] in filled for n in layer_norms), graph  # no stored ones, zeros
    with pytest.raises(SystemExit, match="off the graph"):
        rebuild_main([str(exported / "sr.onnx"), "--reexport", str(tmp_path / "bad.onnx"), "--groups", "1"])


def test_the_shipped_sr_can_be_fine_tuned_without_its_runs(tmp_path):
    """The installed SR graph (mirror-averaged) rebuilds into a geometry-guided checkpoint within the export's
    parity bound, with the light maps it was trained on and its card blur; the installed AOP (the mean of two
    networks) rebuilds one member at a time (``--member``), and without one is refused with a message."""
    from training import checkpoint
    from training.onnx_weights import main as rebuild_main

    from ssn_engine.methods import MODEL_DIR as models

    assert rebuild_main([str(models / "sr.onnx"), "--out", str(tmp_path / "sr.pt")]) == 0
    ck = checkpoint.load(tmp_path / "sr.pt")
    assert ck["parity"] <= 1e-4 and ck["module"] == "sr" and ck["unet"]["card"] is True
    meta = json.loads((models / "model.json").read_text())
    assert ck["training"] == meta["sr_training"]  # for the next card
    assert ck["mirror_average"] == meta["mirror_average"]  # the network inside the graph's mirror average
    assert ck["args"]["lights"] == "mix" and meta["lights"].startswith("the family mixture")
    assert ck["args"]["card_blur"] == meta["card_blur"] > 0  # an export of it blurs the card as the engine did
    with pytest.raises(SystemExit, match="mean of 2 networks: give --member"):
        rebuild_main([str(models / "aop.onnx"), "--out", str(tmp_path / "aop.pt")])
    for k in (0, 1):  # the installed AOP's members: their mean rebuilt is checked against the graph
        assert rebuild_main([str(models / "aop.onnx"), "--member", str(k), "--out", str(tmp_path / f"aop{k}.pt")]) == 0
        ck = checkpoint.load(tmp_path / f"aop{k}.pt")
        assert ck["parity"] <= 1e-4 and ck["module"] == "aop" and ck["member"] == k
    first, second = (checkpoint.load(tmp_path / f"aop{k}.pt")["model"] for k in (0, 1))
    assert any(not torch.equal(first[key], second[key]) for key in first)  # two different networks
    with pytest.raises(SystemExit, match="single network"):
        rebuild_main([str(models / "sr.onnx"), "--member", "0", "--out", str(tmp_path / "sr0.pt")])


def test_a_camera_taking_aop_exports_beside_the_plain_one_and_serves_calls_with_a_camera(exported, tmp_path):
    """An AOP trained with --camera exports as aop_camera.onnx ("camera" in frames) beside the plain AOP; the
    engine runs it for calls that give the camera input and the plain AOP for blind ones; --aop refuses it."""
    from ssn_engine.methods import OnnxSSN
    from training import checkpoint
    from training.graph_weights import rebuild

    run = tmp_path / "aop_cam"
    assert train_main(["--module", "aop", "--camera", "--run", str(run), *TINY], store=FakeStore(res=32)) == 0
    ck = checkpoint.load(run / "last.pt")
    ck["model"]["unet.head.bias"].fill_(0.5)  # AO maps away from the clamp at 1, where camera changes would not show
    checkpoint.save(run / "last.pt", ck)
    sr, out = exported.parent / "sr" / "last.pt", tmp_path / "model"
    assert export([run / "last.pt"], sr, tmp_path / "bad", tmp_path / "no-data") == 1
    options = ("--ao-gamma", "0.6", "--aop-camera", str(run / "last.pt"))  # the fixture's gamma
    assert export([exported / "aop.onnx"], sr, out, tmp_path / "no-data", *options) == 0
    graph = ort.InferenceSession(str(out / "aop_camera.onnx"))
    assert {i.name for i in graph.get_inputs()} == {"mask", "camera"}
    card = json.loads((out / "model.json").read_text())
    assert card["aop_camera"] == "aop_camera.onnx" and card["export"]["aop_camera"]["max_abs_diff"] <= 1e-4
    assert "- AOP with camera: " in (out / "MODEL_CARD.md").read_text()
    method, plain = OnnxSSN(out), OnnxSSN(exported)
    mask = np.zeros((1, 256, 256), np.float32)
    mask[0, 40:200, 100:156] = 1.0
    np.testing.assert_array_equal(method.predict_ao(mask), plain.predict_ao(mask))  # blind: the plain AOP
    level, steep = (method.predict_ao(mask, np.array([[h, 300.0]])) for h in (150.0, -100.0))
    assert np.abs(level - steep).max() > 1e-3  # the camera reaches the camera-taking AOP
    net, ck = rebuild(out / "aop_camera.onnx", groups=2)  # the shipped graph can be fine-tuned without its run
    assert ck["unet"]["camera"] and ck["parity"] <= 1e-4
