"""ONNX graphs of the torch networks: export with the contract's names, rewrites of exported graphs, parity.

- :func:`export_graph`: ``torch.onnx.export`` of an AOP or SR with the engine's input and output names
  (ssn_engine/methods/onnx_ssn.py), each GroupNorm as two fused kernels (:class:`FixedGroupNorm`), the output
  clamped to [0, 1], a dynamic batch axis.
- :func:`without_mirror_average`: a mirror-averaged graph rewritten to run its network once.
- :func:`half_weights`: a graph's weights stored in half precision, cast back as it loads.
- :func:`parity`: the largest difference between a graph and its torch network.
"""

from __future__ import annotations

import copy
from pathlib import Path

import numpy as np
import onnx
import onnx.utils
import onnxruntime as ort
import torch
from onnx import helper, numpy_helper
from torch import nn

from .model import AOPNet, Ensemble, MirrorAverage, SRNet, UNetConfig

__all__ = [
    "TOL",
    "Clamped",
    "FixedGroupNorm",
    "export_graph",
    "fill_norm_constants",
    "for_export",
    "half_weights",
    "mirror_concat",
    "parity",
    "session",
    "takes_camera",
    "takes_card",
    "without_mirror_average",
]

TOL = 1e-4  # the largest difference a graph may have to its torch network


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


def export_graph(
    net: nn.Module, module: str, resolution: int, path: Path, opset: int = 18, output: str | None = None
) -> None:
    """torch.onnx.export with the contract's names and a dynamic batch axis (``output``: another name for the
    output, as the surface model's "height" from an AOP's network)."""
    mask = torch.rand(2, 1, resolution, resolution)
    if module == "aop":
        args, names, out = (mask,), ["mask"], [output or "ao"]
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


def half_weights(path: Path, smallest: int = 1024) -> None:
    """Rewrite the graph at ``path`` with each float32 initializer of at least ``smallest`` values stored in
    float16 and cast back to float32 by a Cast node (folded when onnxruntime loads the graph, so that it runs in
    float32 as before): half the bytes, each weight within 2^-11 of itself."""
    model = onnx.load(str(path))
    g = model.graph
    casts, kept = [], []
    for init in g.initializer:
        array = numpy_helper.to_array(init)
        if array.dtype != np.float32 or array.size < smallest:
            kept.append(init)
            continue
        kept.append(numpy_helper.from_array(array.astype(np.float16), init.name + "_half"))
        casts.append(helper.make_node("Cast", [init.name + "_half"], [init.name], to=onnx.TensorProto.FLOAT))
    del g.initializer[:]
    g.initializer.extend(kept)
    nodes = casts + list(g.node)
    del g.node[:]
    g.node.extend(nodes)
    onnx.checker.check_model(model)
    onnx.save(model, str(path))


def fill_norm_constants(path: Path) -> None:
    """Rewrite the exported graph at ``path`` without its LayerNormalizations' full-size constants: the exporter
    stores a scale of ones and a bias of zeros the size of each normalised group (2 MB in the AOP); the ones
    become a ConstantOfShape (folded when onnxruntime loads the graph) and the zeros, an optional input, go."""
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


def _config(net: nn.Module) -> UNetConfig:
    """The UNetConfig of a network, possibly wrapped in MirrorAverage / Ensemble."""
    while isinstance(net, (MirrorAverage, Ensemble)):
        net = net.net if isinstance(net, MirrorAverage) else net.nets[0]
    if not isinstance(net, (AOPNet, SRNet)):
        raise TypeError(f"expected an AOP or SR network, got {type(net).__name__}")
    return net.config


def takes_card(net: nn.Module) -> bool:
    """Whether an SR network is geometry-guided."""
    return bool(_config(net).card)


def takes_camera(net: nn.Module) -> bool:
    """Whether an AOP network takes the camera input."""
    return bool(_config(net).camera)


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


def session(path: Path, threads: int = 0) -> ort.InferenceSession:
    """An onnxruntime CPU session of the graph at ``path`` with every graph optimisation (``threads``: 0, its
    default)."""
    o = ort.SessionOptions()
    o.graph_optimization_level = ort.GraphOptimizationLevel.ORT_ENABLE_ALL
    if threads:
        o.intra_op_num_threads = threads
    return ort.InferenceSession(str(path), o, providers=["CPUExecutionProvider"])


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
