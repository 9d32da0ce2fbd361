"""Export AOP and SR to the engine's ONNX contract, check parity with torch, time SR, and optionally install.

``python -m training.export --aop runs/aop/last.pt --sr runs/sr/last.pt --out runs/export``
writes aop.onnx, sr.onnx and model.json (the contract of ssn_engine/methods/onnx_ssn.py):
- aop.onnx: "mask" [batch, 1, R, R] -> "ao" [batch, 1, R, R], clamped to [0, 1]
- aop_camera.onnx (--aop-camera): an AOP trained with the camera input (train --camera), which also takes
  "camera" [batch, 2], horizon row and focal length in frames (pixels / N)
- sr.onnx: "mask", "ao" [batch, 1, R, R], "elm" [batch, 16, 32] (network_elm-normalised) -> "shadow" [batch, 1, R, R];
  a geometry-guided SR (train --card) also takes "card" [batch, 1, R, R], the geometric card's shadow
``--aop`` may name an installed aop.onnx instead of checkpoints: that graph is reused as it is (its record is read
from the model.json beside it), so a new SR can ship with the AOP of an earlier release.
Weights are stored as float32 unless float16 keeps the parity bound: the float16 graph (exported from the
torch model with float16-rounded weights, cast back to float32 inside the graph) must stay within ``--tol``
of that model and within ``--max-shift`` (default: ``--tol`` as well) of the checkpoint itself.
``--install DIR`` copies the model and a model card there (the engine's default is ssn_engine/models).
"""

from __future__ import annotations

import argparse
import json
import shutil
import sys
import time
from pathlib import Path
from typing import TYPE_CHECKING

import numpy as np
import torch
from torch import nn

from .checkpoint import load_models
from .elm import TRAIN_MIX
from .model import MirrorAverage

if TYPE_CHECKING:
    import onnx

TOL = 1e-4
MIX_RECORD = "the family mixture"  # model.json "lights" of an SR trained with --lights mix


class FixedGroupNorm(nn.Module):
    """GroupNorm as two fused onnxruntime kernels: a LayerNormalization over each group's (channels, height,
    width), then the per-channel weight and bias as a BatchNormalization of mean 0 and variance 1 (one pass
    instead of a Mul and an Add). ``shape`` (channels, height, width) is the input's, fixed at export, so the
    graph holds no shape arithmetic. onnxruntime 1.32's LayerNormalization is within 5e-6 of float64 over
    8 x 4 x 128 x 128 values of mean 100 (1.16's SR output within 2.4e-5 of 1.32's); it and the BatchNormalization
    took the mirror-averaged SR from 11.9 to 10.1 ms at R = 128 (the chained means it replaced, docs/engine.md)."""

    def __init__(self, gn: nn.GroupNorm, shape: tuple[int, int, int]):
        super().__init__()
        self.groups, self.eps, self.shape = gn.num_groups, gn.eps, shape
        self.weight, self.bias = gn.weight, gn.bias

    def forward(self, x: torch.Tensor) -> torch.Tensor:
        c, h, w = self.shape
        g = self.groups
        d = nn.functional.layer_norm(x.reshape(-1, g, c // g, h, w), (c // g, h, w), eps=self.eps)
        zeros, ones = torch.zeros(c), torch.ones(c)
        return nn.functional.batch_norm(d.reshape(-1, c, h, w), zeros, ones, self.weight, self.bias, eps=0.0)


def for_export(net: nn.Module, *inputs: torch.Tensor) -> nn.Module:
    """A copy of ``net`` with :class:`FixedGroupNorm` in place of every GroupNorm, each fixed to the shape it
    sees when the copy runs on ``inputs``."""
    import copy

    net = copy.deepcopy(net).eval()
    shapes: dict[nn.Module, tuple[int, int, int]] = {}
    norms = [m for m in net.modules() if isinstance(m, nn.GroupNorm)]
    hooks = [m.register_forward_pre_hook(lambda m, a: shapes.__setitem__(m, tuple(a[0].shape[1:]))) for m in norms]
    with torch.no_grad():
        net(*inputs)
    for hook in hooks:
        hook.remove()

    def swap(module: nn.Module) -> None:
        for name, child in module.named_children():
            if isinstance(child, nn.GroupNorm):
                setattr(module, name, FixedGroupNorm(child, shapes[child]))
            else:
                swap(child)

    swap(net)
    return net


class Clamped(nn.Module):
    """The network with its output clamped to [0, 1] (the contract's range)."""

    def __init__(self, net: nn.Module):
        super().__init__()
        self.net = net

    def forward(self, *inputs: torch.Tensor) -> torch.Tensor:
        return self.net(*inputs).clamp(0.0, 1.0)


def export_graph(net: nn.Module, module: str, resolution: int, path: Path, opset: int = 18) -> None:
    """torch.onnx.export with the contract's names and a dynamic batch axis."""
    mask = torch.rand(2, 1, resolution, resolution)
    if module == "aop":
        args, names, out = (mask,), ["mask"], ["ao"]
        if takes_camera(net):
            args, names = args + (torch.tensor([[0.4, 1.2], [0.6, 1.0]]),), names + ["camera"]
    else:
        args, names, out = (
            (mask, torch.rand(2, 1, resolution, resolution), torch.rand(2, 16, 32)),
            ["mask", "ao", "elm"],
            ["shadow"],
        )
        if takes_card(net):
            args, names = args + (torch.rand(2, 1, resolution, resolution),), names + ["card"]
    axes = {n: {0: "batch"} for n in names + out}
    torch.onnx.export(
        Clamped(for_export(net, *args)).eval(),
        args,
        str(path),
        input_names=names,
        output_names=out,
        dynamic_axes=axes,
        opset_version=opset,
        dynamo=False,
    )
    fill_norm_constants(path)


def fill_norm_constants(path: Path) -> None:
    """Rewrite the exported graph at ``path`` without its LayerNormalizations' full-size constants: the exporter
    stores a scale of ones and a bias of zeros the size of each normalised group (2 MB in the AOP); the ones
    become a ConstantOfShape (folded when onnxruntime loads the graph) and the zeros, an optional input, go."""
    import onnx
    from onnx import helper, numpy_helper

    model = onnx.load(str(path))
    g = model.graph
    constants = {n.output[0]: n for n in g.node if n.op_type == "Constant" and n.attribute[0].name == "value"}

    def filled(name: str, value: float) -> np.ndarray | None:
        node = constants.get(name)
        if node is None:
            return None
        array = numpy_helper.to_array(node.attribute[0].t)
        return array if array.size > 1 and np.all(array == value) else None

    fills, renamed = [], {}  # the ConstantOfShape nodes; each stored scale's name -> its fill's
    for norm in (n for n in g.node if n.op_type == "LayerNormalization"):
        if len(norm.input) > 2 and filled(norm.input[2], 0.0) is not None:
            del norm.input[2]
        ones = filled(norm.input[1], 1.0)
        if ones is not None and norm.input[1] not in renamed:
            shape = numpy_helper.from_array(np.array(ones.shape, np.int64), norm.input[1] + "_shape")
            value = numpy_helper.from_array(np.ones(1, np.float32))
            renamed[norm.input[1]] = norm.input[1] + "_filled"
            fills += [
                helper.make_node("Constant", [], [shape.name], value=shape),
                helper.make_node("ConstantOfShape", [shape.name], [renamed[norm.input[1]]], value=value),
            ]
        norm.input[1] = renamed.get(norm.input[1], norm.input[1])
    used = {i for n in g.node for i in n.input} | {o.name for o in g.output}
    nodes = fills + [n for n in g.node if n.op_type != "Constant" or n.output[0] in used]
    del g.node[:]
    g.node.extend(nodes)
    onnx.checker.check_model(model)
    onnx.save(model, str(path))


def _config(net: nn.Module):
    """The UNetConfig of a network, possibly wrapped in MirrorAverage / Ensemble."""
    while not hasattr(net, "config"):
        net = net.net if hasattr(net, "net") else net.nets[0]
    return net.config


def takes_card(net: nn.Module) -> bool:
    """Whether an SR network is geometry-guided."""
    return bool(_config(net).card)


def takes_camera(net: nn.Module) -> bool:
    """Whether an AOP network takes the camera input."""
    return bool(_config(net).camera)


def to_fp16_weights(src: Path, dst: Path) -> None:
    """Store every float32 initializer as float16 followed by a Cast back to float32 (compute stays float32)."""
    import onnx
    from onnx import TensorProto, helper, numpy_helper

    model = onnx.load(str(src))
    g = model.graph
    new_inits, casts = [], []
    for init in g.initializer:
        arr = numpy_helper.to_array(init)
        if arr.dtype == np.float32 and arr.size > 16:
            half = numpy_helper.from_array(arr.astype(np.float16), init.name + "__fp16")
            new_inits.append(half)
            casts.append(helper.make_node("Cast", [half.name], [init.name], to=TensorProto.FLOAT))
        else:
            new_inits.append(init)
    del g.initializer[:]
    g.initializer.extend(new_inits)
    nodes = list(g.node)
    del g.node[:]
    g.node.extend(casts + nodes)
    onnx.checker.check_model(model)
    onnx.save(model, str(dst))


def mirror_concat(model: onnx.ModelProto) -> onnx.NodeProto | None:
    """The node of a graph exported from :class:`training.model.MirrorAverage` that doubles its batch: the one
    Concat of the first input and a Slice of it (its mirror image); None if the graph has no such node."""
    g = model.graph
    source = g.input[0].name
    starts = [n for n in g.node if n.op_type == "Concat" and list(n.input)[:1] == [source]]
    slices = {o for n in g.node if n.op_type == "Slice" and n.input[0] == source for o in n.output}
    return starts[0] if len(starts) == 1 and len(starts[0].input) > 1 and starts[0].input[1] in slices else None


def without_mirror_average(src: Path, dst: Path) -> None:
    """Rewrite a graph exported from :class:`training.model.MirrorAverage` (its network run on ``cat([x,
    flip(x)])``, the halves averaged) into the network run once on ``x``: half the compute. The shipped AOP's
    checkpoints are gone; its graph is all there is to rewrite."""
    import onnx
    import onnx.utils

    model = onnx.load(str(src))
    g = model.graph
    producer = {o: n for n in g.node for o in n.output}
    source, output = g.input[0].name, g.output[0].name

    def made_by(name: str, op: str):
        node = producer.get(name)
        if node is None or node.op_type != op:
            raise ValueError(f"{src} is not a mirror-averaged graph: expected {op} to make {name!r}")
        return node

    # output <- Clip(Mul(Add(Slice(y), Slice(Slice(y))), 0.5)): y is the network's output on the doubled batch
    clip = made_by(output, "Clip")
    mul = made_by(clip.input[0], "Mul")
    first_half = made_by(made_by(mul.input[0], "Add").input[0], "Slice")
    network_out = first_half.input[0]
    doubled = mirror_concat(model)
    if doubled is None:
        raise ValueError(f"{src} is not a mirror-averaged graph: no Concat of {source!r} and its mirror image")
    for node in g.node:
        node.input[:] = [source if name == doubled.output[0] else name for name in node.input]
    clip.input[0] = network_out
    rewired = dst.with_suffix(".rewired.onnx")
    onnx.save(model, str(rewired))
    onnx.utils.extract_model(str(rewired), str(dst), [source], [output])  # drops the now unused mirror nodes
    rewired.unlink()
    onnx.checker.check_model(onnx.load(str(dst)))


def rounded_to_fp16(net: nn.Module) -> nn.Module:
    """A copy of ``net`` whose parameters are rounded to float16 (kept as float32 tensors)."""
    import copy

    out = copy.deepcopy(net)
    with torch.no_grad():
        for p in out.parameters():
            p.copy_(p.half().float())
    return out.eval()


def session(path: Path, threads: int = 0):
    import onnxruntime as ort

    o = ort.SessionOptions()
    o.graph_optimization_level = ort.GraphOptimizationLevel.ORT_ENABLE_ALL
    if threads:
        o.intra_op_num_threads = threads
    return ort.InferenceSession(str(path), o, providers=["CPUExecutionProvider"])


def test_inputs(data: str | None, resolution: int, n: int = 8, seed: int = 0) -> dict[str, np.ndarray]:
    """Masks and AO maps of test views (random blobs without data) and random Table 1 ELMs."""
    from ssn_engine.frames import resample_frames
    from ssn_engine.hemisphere import network_elm

    from .elm import render_lights, sample_lights

    rng = np.random.default_rng(seed)
    if data and Path(data, "dataset.json").is_file():
        from .data.store import ViewStore

        store = ViewStore(data)
        ids = store.view_ids("test") or store.view_ids(None)
        pick = [ids[int(j)] for j in np.linspace(0, len(ids) - 1, n).round()]
        views = [store.load(i) for i in pick]
        mask = resample_frames(np.stack([v.mask for v in views]), resolution)
        ao = resample_frames(np.stack([v.ao for v in views]), resolution)
    else:
        mask = (rng.random((n, resolution, resolution)) > 0.5).astype(np.float32)
        ao = rng.random((n, resolution, resolution)).astype(np.float32)
    elm = network_elm(render_lights(sample_lights(rng, n), 16))
    card = rng.random((n, 1, resolution, resolution)).astype(np.float32) * mask[:, None]
    camera = np.stack([rng.uniform(-0.3, 1.3, n), rng.uniform(0.9, 1.6, n)], axis=1).astype(np.float32)
    return {"mask": mask[:, None], "ao": ao[:, None], "elm": elm, "card": card, "camera": camera}


def parity(path: Path, net: nn.Module, module: str, x: dict[str, np.ndarray]) -> float:
    """Max abs difference between onnxruntime and torch (clamped) outputs."""
    if module == "aop":
        names = ["mask"] + (["camera"] if takes_camera(net) else [])
    else:
        names = ["mask", "ao", "elm"] + (["card"] if takes_card(net) else [])
    feeds = {k: x[k] for k in names}
    got = session(path).run(None, feeds)[0]
    with torch.no_grad():
        ref = Clamped(net)(*[torch.from_numpy(x[k]) for k in names]).numpy()
    return float(np.abs(got - ref).max())


def time_sr(path: Path, resolution: int, repeats: int = 30) -> dict[str, float]:
    """Median SR latency (one image) through onnxruntime: at R alone, and the engine's N = 256 path."""
    from ssn_engine.frames import resample_frames

    s = session(path)
    card = "card" in {i.name for i in s.get_inputs()}
    mask = np.random.default_rng(0).random((1, 1, resolution, resolution), dtype=np.float32)
    feeds = {"mask": mask, "ao": mask, "elm": np.random.default_rng(1).random((1, 16, 32), dtype=np.float32)}
    feeds.update({"card": mask} if card else {})
    frame = np.random.default_rng(2).random((1, 256, 256), dtype=np.float32)

    def engine_path():
        m = resample_frames(frame, resolution)[:, None]
        out = s.run(None, {"mask": m, "ao": m, "elm": feeds["elm"], **({"card": m} if card else {})})[0][:, 0]
        return resample_frames(out, 256)

    out = {}
    for name, fn in (("sr_at_R_ms", lambda: s.run(None, feeds)), ("sr_engine_256_ms", engine_path)):
        fn()
        ts = []
        for _ in range(repeats):
            t = time.perf_counter()
            fn()
            ts.append(time.perf_counter() - t)
        out[name] = 1000 * float(np.median(ts))
    return out


def mesh_attribution(data: str) -> list[dict]:
    """Licence and attribution of every mesh in the dataset's train and val splits."""
    from .data.store import ViewStore

    if not Path(data, "dataset.json").is_file():
        return []
    store = ViewStore(data)
    rows = []
    for m in store.meshes:
        mesh = m["mesh"]
        p = mesh.get("params", {})
        if mesh["split"] in ("train", "val"):
            rows.append(
                {
                    "id": mesh["id"],
                    "split": mesh["split"],
                    "licence": p.get("licence", "generated"),
                    "attribution": p.get("attribution", "procedural / project-generated"),
                    "source": p.get("source_repo", mesh.get("source", "")),
                }
            )
    return rows


def model_card(card: dict, attribution: list[dict], command: str) -> str:
    """The model card (markdown) shipped next to model.json."""
    ex = card["export"]
    lines = [
        "# SSN shadow model (AOP + SR)",
        "",
        "The paper's Soft Shadow Network (Sheng et al., CVPR 2021) as two ONNX graphs for "
        "`ssn_engine.methods.onnx_ssn`: AOP (mask -> AO map A^(1/3)) and SR (mask, AO, 16 x 32 ELM -> shadow s,",
        "the conventions' normalised inverse shadow).",
        "",
        f"- Resolution R = {card['resolution']} (the engine resamples its 256 x 256 frames to R and back).",
    ]
    for m in ("aop", "sr", "aop_camera"):
        if m not in ex:
            continue
        r = ex[m]
        rebuilt = r.get("rebuilt_from") or [None] * len(r["checkpoints"])
        runs = " and ".join(
            f"U-Net widths {w}, " + (f"the network of `{g}` (`{p}`)" if g else f"{st} steps ({n} samples, `{p}`)")
            for p, w, st, n, g in zip(r["checkpoints"], r["widths"], r["steps"], r["samples"], rebuilt, strict=True)
        )
        mean = f"the mean of {len(r['checkpoints'])} networks, " if len(r["checkpoints"]) > 1 else ""
        reused = ""
        if r.get("reused_from"):
            how = "without its mirror average" if r.get("mirror_average") is False else "as it is"
            reused = f" (the graph of `{r['reused_from']}`, reused {how})"
        label, camera = m.upper(), ""
        if m == "aop_camera":
            label = "AOP with camera"
            camera = " (for calls that give the camera input: it also takes the horizon row and focal length)"
        lines.append(
            f"- {label}: {mean}{runs}{reused}{camera}, {r['weights']} weights, "
            f"{r['bytes'] / 1e6:.2f} MB, max abs diff to torch {r['max_abs_diff']:.1e}"
        )
    if card.get("height"):
        lines.append(
            f"- Height proxy ({card['height']}, {ex['height']['bytes'] / 1e6:.2f} MB, "
            f"from `{ex['height']['source']}`): "
            "a U-Net reads the near and far pixel heights of every masked pixel and the camera (horizon row, "
            "focal length) from the mask; the cutout becomes the volume between those two surfaces, placed with "
            f"the camera input or, blind, the estimate, and its hard shadows are traced on a {card['proxy_internal']} "
            "grid (`ssn_engine.methods.height_proxy`). The SR takes that proxy's shadow where a flat card's was."
        )
    if card.get("card_input"):
        lines.append(
            "- Geometry-guided SR: it also takes the engine's geometric card shadow for the same light map "
            "(since v3.9 a texel holding 5 % of the light casts the mean shadow over its area; traced with the "
            "camera input when given, else the model's camera estimator's reading of the mask, or without one the "
            "conventions' default camera) and outputs a "
            "correction of it, so the shadow's direction and length come from the card's geometry and the "
            f"network refines contact, softness and shape. Light maps in training: {card['lights']}."
        )
    if card.get("output_floor"):
        lines.append(
            f"- Output floor {card['output_floor']}: the engine maps s to (s - floor) / (1 - floor), clipped "
            "(removes the network's faint noise; chosen on the validation split, docs/benchmark.md)."
        )
    if "output_floor_small_lights" in card:
        lines.append(
            f"- Output floor {card['output_floor_small_lights']} for one or two small lights, blended in as the "
            "light map's energy concentrates in its 16 brightest texels (a hard shadow has no faint tails, so "
            "faint values there are haze; onnx_ssn.floor_for; chosen on the validation split, docs/training.md)."
        )
    if card.get("shadow_reach"):
        lines.append(
            f"- Shadow reach {card['shadow_reach']} pixels (N = 256): for one or two small lights the engine keeps "
            "the network's shadow within that distance of the card's shadow and of the cutout and fades it out "
            "beyond, where no occluder can cast and what the network leaves is haze (onnx_ssn.reach_weights; "
            "chosen on the validation split, docs/training.md)."
        )
    if card.get("ao_gamma", 1.0) != 1.0:
        lines.append(
            f"- AO gamma {card['ao_gamma']}: the engine uses the predicted AO map raised to this power, lighter "
            "where the AOP darkens objects more than their true AO; the SR gains on every light family "
            "(chosen on the validation split, docs/training.md)."
        )
    if card.get("card_blur"):
        lines.append(
            f"- Card blur {card['card_blur']} pixels (R): the engine blurs the card's shadow by a Gaussian of this "
            "size before the SR sees it; the card's aliased steps at a wedge's tip made the SR leave speckles "
            "(onnx_ssn.blur_frames; checked on the validation split, docs/training.md)."
        )
    if card.get("mirror_average"):
        # a reused AOP keeps its own mirror average or none (as the shipped one), as does --aop-camera's
        which = (
            "the SR graph" if ex["aop"].get("reused_from") or ex["aop"].get("mirror_average") is False else "each graph"
        )
        lines.append(
            f"- Mirror average: {which} runs its network on the input and on its mirror image (frames in x, the "
            "ELM in azimuth) and averages the two (training.model.MirrorAverage)."
        )
    if card.get("sr_training"):
        lines.append(f"- SR training: {card['sr_training']}.")
    t = ex["timing"]
    lines += [
        f"- SR latency (onnxruntime, median, 2-core CPU): {t['sr_at_R_ms']:.1f} ms at R, "
        f"{t['sr_engine_256_ms']:.1f} ms for a 256 frame including resampling.",
        "",
        "## Training data",
        "",
        f"Shadow bases of `{card.get('training_data')}` (training/data, `python -m training.make_dataset`), "
        "train split; soft shadows from random light maps on the fly (Table 1, or the mixture of light families "
        "of `training.elm`), exact linear algebra on the bases.",
        "",
    ]
    if "metrics" in card:
        from .evaluate import tables_markdown

        lines += ["## Test metrics (`python -m training.evaluate`)", "", tables_markdown(card["metrics"]), ""]
    lines += [
        "## Reproduce",
        "",
        "```",
        command,
        "```",
        "",
        "## Mesh attribution",
        "",
        "The training meshes are CC BY (attribution below), CC0 or public domain. Per mesh:",
        "",
        "| mesh | licence | attribution | source |",
        "|---|---|---|---|",
    ]
    lines += [f"| {a['id']} | {a['licence']} | {a['attribution']} | {a['source']} |" for a in attribution]
    return "\n".join(lines) + "\n"


def training_summary(path: Path, ck: dict) -> str:
    """How long a checkpoint trained (from its run's log.csv), following ``--init-from`` back to the run it was
    fine-tuned from (a checkpoint rebuilt from a graph, :mod:`training.onnx_weights`, carries its record)."""
    if "rebuilt_from" in ck:
        return ck.get("training") or f"the network of {ck['rebuilt_from']}"
    log = path.with_name("log.csv")
    rows = log.read_text().splitlines()[1:] if log.is_file() else []
    minutes = f"{float(rows[-1].split(',')[5]) / 60:.0f} min of training time, " if rows else ""
    args = ck.get("args") or {}
    terms = [
        f"{args[k]:g} x {name}" for k, name in (("ssim_weight", "DSSIM"), ("zncc_weight", "(1 - ZNCC)")) if args.get(k)
    ]
    loss = f" (loss: L2 + {' + '.join(terms)})" if terms else ""
    text = f"{minutes}{ck['step']} steps, {ck['samples']} samples{loss}"
    parent = args.get("init_from")
    if parent and Path(parent).is_file():
        text = (
            f"{training_summary(Path(parent), load_models([parent])[1][0])}, then fine-tuned for {text} "
            f"(learning rate {args['lr']:g})"
        )
    return text


def reuse_aop(graph: Path, out: Path, drop_mirror: bool = False) -> dict:
    """Copy an installed aop.onnx into ``out`` (``drop_mirror``: :func:`without_mirror_average` of it); its record
    from the model.json beside it (or a bare one)."""
    if drop_mirror:
        without_mirror_average(graph, out / "aop.onnx")
    elif graph.resolve() != (out / "aop.onnx").resolve():
        shutil.copy(graph, out / "aop.onnx")
    meta = graph.with_name("model.json")
    record = json.loads(meta.read_text())["export"]["aop"] if meta.is_file() else {}
    return {
        "checkpoints": [],
        "steps": [],
        "samples": [],
        "widths": [],
        "weights": "float32",
        "max_abs_diff": 0.0,
        **record,
        "bytes": (out / "aop.onnx").stat().st_size,
        "reused_from": str(graph),
        **({"mirror_average": False} if drop_mirror else {}),
    }


def parse_args(argv: list[str] | None = None) -> argparse.Namespace:
    p = argparse.ArgumentParser(prog="python -m training.export", description=__doc__.split("\n")[0])
    p.add_argument(
        "--aop",
        nargs="+",
        required=True,
        help="AOP checkpoint(s); several: one graph of their mean; or an installed aop.onnx, reused as it is",
    )
    p.add_argument(
        "--aop-camera",
        nargs="+",
        help="camera-taking AOP checkpoint(s) (train --camera; several: their mean): aop_camera.onnx, the AOP "
        "the engine runs for calls that give the camera input",
    )
    p.add_argument("--sr", required=True)
    p.add_argument("--out", default="runs/export")
    p.add_argument("--data", default="data/ssn128", help="dataset for test inputs and the card's attribution")
    p.add_argument("--tol", type=float, default=TOL)
    p.add_argument("--fp32", action="store_true", help="do not try float16 weights")
    p.add_argument(
        "--max-shift",
        type=float,
        default=None,
        help="largest output change that rounding the weights to float16 may cause (default: --tol)",
    )
    p.add_argument("--metrics", help="evaluate's results.json, copied into the card")
    p.add_argument(
        "--floor",
        type=float,
        default=0.0,
        help="model.json output_floor: the engine removes shadow values below it (evaluate --floor)",
    )
    p.add_argument(
        "--floor-small-lights",
        type=float,
        default=None,
        help="model.json output_floor_small_lights: the floor for one or two small lights (default: --floor)",
    )
    p.add_argument(
        "--shadow-reach",
        type=float,
        default=0.0,
        help="model.json shadow_reach: keep the shadow within this many pixels (N = 256) of the card's shadow "
        "and the cutout (a geometry-guided SR only; 0: off)",
    )
    p.add_argument(
        "--ao-gamma",
        type=float,
        default=1.0,
        help="model.json ao_gamma: the engine raises the predicted AO map to this power (1: as predicted)",
    )
    p.add_argument(
        "--card-blur",
        type=float,
        help="model.json card_blur: blur the card's shadow by a Gaussian of this many pixels (R) before the SR "
        "(a geometry-guided SR only; 0: off; default: the SR's training option, train --card-blur)",
    )
    p.add_argument(
        "--mirror-average",
        action="store_true",
        help="export each network as training.model.MirrorAverage (twice the compute, mirror-symmetric)",
    )
    p.add_argument(
        "--aop-without-mirror",
        action="store_true",
        help="with an installed, mirror-averaged aop.onnx as --aop: reuse it without its mirror average "
        "(each network once; half the AOP's compute)",
    )
    p.add_argument(
        "--height",
        help="a HeightNet graph (python -m training.heights export): ships as height.onnx, and the engine feeds "
        "the SR the height proxy's shadow in the card's place (an SR trained with --proxy)",
    )
    p.add_argument(
        "--proxy-internal", type=int, default=64, help="--height: model.json proxy_internal, the proxy's tracing grid"
    )
    p.add_argument("--install", help="copy the model here (e.g. ssn_engine/models)")
    p.add_argument(
        "--command",
        default="training/pipeline.sh data/ssn128 runs",
        help="the reproducing command recorded in the card",
    )
    p.add_argument("--trained-on", default="", help="the machine the SR was trained on, for the card")
    return p.parse_args(argv)


def main(argv: list[str] | None = None) -> int:
    args = parse_args(argv)
    if args.max_shift is None:
        args.max_shift = args.tol
    reused = len(args.aop) == 1 and args.aop[0].endswith(".onnx")
    if args.aop_without_mirror and not reused:
        raise SystemExit("--aop-without-mirror rewrites an installed aop.onnx: give one as --aop")
    if args.height and not args.height.endswith(".onnx"):
        raise SystemExit(f"--height {args.height}: give the graph of python -m training.heights export (.onnx)")
    out = Path(args.out)
    out.mkdir(parents=True, exist_ok=True)
    card: dict = {
        "format": "ssn-shadow-model",
        "version": 1,
        "aop": "aop.onnx",
        "sr": "sr.onnx",
        "elm_shape": [16, 32],
        "output_floor": args.floor,
        "mirror_average": args.mirror_average,
    }
    if args.floor_small_lights is not None:
        card["output_floor_small_lights"] = args.floor_small_lights
    if args.shadow_reach:
        card["shadow_reach"] = args.shadow_reach
    if args.ao_gamma != 1.0:
        card["ao_gamma"] = args.ao_gamma
    report = {}
    graphs = [("aop", "aop", args.aop), ("sr", "sr", [args.sr])]
    if args.aop_camera:
        graphs.append(("aop_camera", "aop", args.aop_camera))
        card["aop_camera"] = "aop_camera.onnx"
    for name, module, ck_paths in graphs:
        if name == "aop" and reused:
            report["aop"] = reuse_aop(Path(ck_paths[0]), out, args.aop_without_mirror)
            without = " without its mirror average" if args.aop_without_mirror else ""
            print(f"aop: reused {ck_paths[0]}{without}", flush=True)
            continue
        net, cks = load_models(ck_paths)
        if module == "aop" and takes_camera(net) != (name == "aop_camera"):
            print(
                f"--{name.replace('_', '-')}: {' '.join(ck_paths)} must be AOPs "
                f"{'with' if name == 'aop_camera' else 'without'} the camera input (train --camera)",
                file=sys.stderr,
            )
            return 1
        # A camera-taking AOP is not mirror-averaged: its camera input is no image to mirror (the shipped AOP
        # runs once anyway, docs/training.md).
        mirrored = args.mirror_average and name != "aop_camera"
        net = MirrorAverage(net).eval() if mirrored else net
        r = cks[0]["unet"]["resolution"]
        card["resolution"] = r
        x = test_inputs(args.data, r)
        fp32 = out / f"{name}.fp32.onnx"
        export_graph(net, module, r, fp32)
        diff32 = parity(fp32, net, module, x)
        final, diff, dtype = fp32, diff32, "float32"
        if not args.fp32:
            # The float16 model is the checkpoint with its weights rounded to float16: exported from that torch
            # model, checked against it (parity), and against the unrounded checkpoint (the rounding's effect).
            net16 = rounded_to_fp16(net)
            src16, fp16 = out / f"{name}.r16.onnx", out / f"{name}.fp16.onnx"
            export_graph(net16, module, r, src16)
            to_fp16_weights(src16, fp16)
            src16.unlink()
            diff16 = parity(fp16, net16, module, x)
            shift = parity(fp16, net, module, x)
            report[f"{name}_parity_fp16"] = diff16
            report[f"{name}_fp16_vs_fp32_checkpoint"] = shift
            if diff16 <= args.tol and shift <= args.max_shift:
                final, diff, dtype = fp16, diff16, "float16"
        shutil.copy(final, out / f"{name}.onnx")
        report[f"{name}_parity_fp32"] = diff32
        report[name] = {
            "checkpoints": [str(p) for p in ck_paths],
            "steps": [ck["step"] for ck in cks],
            "samples": [ck["samples"] for ck in cks],
            "widths": [ck["unet"]["widths"] for ck in cks],
            "rebuilt_from": [ck.get("rebuilt_from") for ck in cks],  # training.onnx_weights: a graph's network
            "weights": dtype,
            "mirror_average": mirrored,
            "max_abs_diff": diff,
            "bytes": (out / f"{name}.onnx").stat().st_size,
        }
        if diff > args.tol:
            print(f"{name}: parity FAILED: max abs diff {diff:.2e} > {args.tol:.0e}", file=sys.stderr)
            return 1
        print(
            f"{name}: {dtype} weights, max abs diff to torch {diff:.2e} (fp32 graph {diff32:.2e}), "
            f"{report[name]['bytes'] / 1e6:.2f} MB",
            flush=True,
        )
    sr_ck = load_models([args.sr])[1][0]
    card["card_input"] = bool(sr_ck["unet"].get("card"))
    if bool(sr_ck["args"].get("proxy")) != bool(args.height):
        trained = "on the height proxy (train --proxy)" if sr_ck["args"].get("proxy") else "on the flat card"
        must = "must" if args.height is None else "must not"
        print(f"{args.sr} was trained {trained}: --height {must} be given", file=sys.stderr)
        return 1
    if args.height:
        graph = out / "height.onnx"
        shutil.copy(args.height, graph)
        card["height"], card["proxy_internal"] = graph.name, args.proxy_internal
        report["height"] = {"source": args.height, "bytes": graph.stat().st_size}
    on = f", on {args.trained_on}" if args.trained_on else ""
    card["sr_training"] = training_summary(Path(args.sr), sr_ck) + on
    blur = sr_ck["args"].get("card_blur", 0.0) if args.card_blur is None else args.card_blur
    if blur:
        card["card_blur"] = blur
    lights = sr_ck["args"].get("lights", "table1")
    card["lights"] = f"{MIX_RECORD} {TRAIN_MIX}" if lights == "mix" else "the paper's Table 1"
    report["timing"] = time_sr(out / "sr.onnx", card["resolution"])
    print(
        f"SR median latency (onnxruntime, this CPU): {report['timing']['sr_at_R_ms']:.1f} ms at R = "
        f"{card['resolution']}, {report['timing']['sr_engine_256_ms']:.1f} ms on a 256 frame incl. resampling"
    )
    card["export"] = report
    if args.metrics:
        card["metrics"] = json.loads(Path(args.metrics).read_text())
    card["training_data"] = args.data
    (out / "model.json").write_text(json.dumps(card, indent=1))
    attribution = mesh_attribution(args.data)
    (out / "MODEL_CARD.md").write_text(model_card(card, attribution, args.command))
    if args.install:
        dst = Path(args.install)
        dst.mkdir(parents=True, exist_ok=True)
        for name in ("aop.onnx", "sr.onnx", "height.onnx", "model.json", "MODEL_CARD.md"):
            if (out / name).is_file():
                shutil.copy(out / name, dst / name)
            else:
                (dst / name).unlink(missing_ok=True)  # a model without a height graph replaces one with it
        print(f"installed into {dst}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
