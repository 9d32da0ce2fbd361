"""A network rebuilt from an exported ONNX graph: its weights read back, checked against the graph.

The exporter (:mod:`training.onnx_graphs`) keeps the convolutions' names (``net.<parameter>``) and folds each
GroupNorm's weight and bias into two anonymous constants, in the order the forward pass uses them; the network's
own GroupNorms, in module order, take them back. A mirror-averaged graph (``export --mirror-average``, names
``net.net.<parameter>``) gives back the network inside the average; a graph of the mean of several networks (the
shipped AOP, ``nets.<k>.``) gives back the one of ``member k``. ``python -m training.onnx_weights`` is the command.
"""

from __future__ import annotations

import re
from collections.abc import Callable
from pathlib import Path

import numpy as np
import onnx
import torch
from onnx import numpy_helper

from ssn_engine.model_config import ModelConfig, ModelConfigError

from .model import AOPNet, SRNet, UNetConfig, build
from .model.ensemble import Ensemble
from .model.mirror import MirrorAverage
from .model_card import MIX_RECORD
from .onnx_graphs import TOL, export_graph, mirror_concat, parity, session

HEAD = re.compile(r"((?:net\.)+)(?:nets\.(\d+)\.)?unet\.encoder\.0\.0\.0\.weight")  # a U-Net's first weight
HALF = "_half"  # onnx_graphs.half_weights: a weight stored in half precision under its name and this suffix


def _parameter(init) -> tuple[str, np.ndarray]:
    """An initializer's parameter name and its value in float32 (a half-stored weight under its own name)."""
    name, array = init.name, numpy_helper.to_array(init)
    return (name[: -len(HALF)], array.astype(np.float32)) if name.endswith(HALF) else (name, array)


def _heads(model: onnx.ModelProto) -> tuple[str, int]:
    """The graph's parameter-name head (``net.`` from training.export.Clamped, ``net.net.`` inside a
    MirrorAverage) and how many networks' mean it is (training.model.Ensemble's ``nets.<k>.``; 0: one network)."""
    found = [m for i in model.graph.initializer if (m := HEAD.fullmatch(i.name))]
    if not found:
        raise ValueError("the graph holds no U-Net")
    return found[0].group(1), len({m.group(2) for m in found if m.group(2) is not None})


def weights_prefix(model: onnx.ModelProto, member: int | None = None) -> str:
    """The prefix of one network's parameter names: the graph's only network, or ``member`` of an ensemble."""
    head, count = _heads(model)
    if count == 0:
        if member is not None:
            raise ValueError("the graph holds a single network: leave out --member")
        return head
    if member is None or not 0 <= member < count:
        raise ValueError(f"the graph is the mean of {count} networks: give --member 0 to {count - 1}")
    return f"{head}nets.{member}."


def _serial(name: str) -> int:
    """The exporter's running number of an anonymous constant (``onnx::Mul_1935`` -> 1935)."""
    found = re.search(r"_(\d+)$", name)
    if found is None:
        raise ValueError(f"unexpected constant {name!r} in the graph")
    return int(found.group(1))


def folded_constants(inits, named: Callable[[str], bool]) -> list[np.ndarray]:
    """The anonymous constants among a graph's initializers (those ``named`` refuses), in the exporter's order:
    each GroupNorm's weight and bias, as the forward pass uses them."""
    return [
        numpy_helper.to_array(i) for i in sorted((i for i in inits if not named(i.name)), key=lambda i: _serial(i.name))
    ]


def graph_config(model: onnx.ModelProto, groups: int = 8, member: int | None = None) -> tuple[str, UNetConfig]:
    """The module ("aop" or "sr") and the U-Net configuration of an exported graph's network (``member`` of an
    ensemble; ``groups``: the GroupNorm groups it was trained with, which the graph keeps only inside its
    reshapes)."""
    inputs = {i.name: i for i in model.graph.input}
    module = "sr" if "elm" in inputs else "aop"
    r = inputs["mask"].type.tensor_type.shape.dim[-1].dim_value
    pattern = re.escape(weights_prefix(model, member)) + r"unet\.encoder\.(\d+)\.0\.0\.weight(?:_half)?"
    convs = {int(m.group(1)): i for i in model.graph.initializer if (m := re.fullmatch(pattern, i.name))}
    widths = tuple(int(convs[k].dims[0]) for k in sorted(convs))
    head = re.escape(weights_prefix(model, member)) + r"unet\.head\.weight(?:_half)?"
    outputs = next((int(i.dims[0]) for i in model.graph.initializer if re.fullmatch(head, i.name)), 1)
    return module, UNetConfig(
        widths=widths,
        groups=groups,
        resolution=int(r),
        card="card" in inputs,
        camera="camera" in inputs,
        outputs=outputs,
    )


def state_dict_from_graph(
    model: onnx.ModelProto, net: torch.nn.Module, member: int | None = None
) -> dict[str, torch.Tensor]:
    """``net``'s state dict with the weights of the graph's network (``member`` of an ensemble, whose members run
    one after the other; shapes checked; every parameter must be found)."""
    inits, prefix = model.graph.initializer, weights_prefix(model, member)
    head, count = _heads(model)
    named = {name[len(prefix) :]: array for name, array in map(_parameter, inits) if name.startswith(prefix)}
    folded = [a.reshape(-1) for a in folded_constants(inits, lambda name: name.startswith(head))]
    target = net.state_dict()
    if count:  # the members' constants follow one another
        n = sum(k not in named for k in target)
        folded = folded[(member or 0) * n : ((member or 0) + 1) * n]
    return fitted(target, named, folded)


def fitted(
    target: dict[str, torch.Tensor], named: dict[str, np.ndarray], folded: list[np.ndarray]
) -> dict[str, torch.Tensor]:
    """The state dict ``target`` filled from a graph: the ``named`` parameters by key, the others (the GroupNorms'
    weight and bias, in module order) from ``folded`` in turn; counts and sizes checked (ValueError)."""
    norms = [k for k in target if k not in named]
    if len(norms) != len(folded):
        raise ValueError(f"the graph folds {len(folded)} normalisation tensors, the network has {len(norms)}")
    out = {}
    for key, array in [*named.items(), *zip(norms, folded, strict=True)]:
        if key not in target or target[key].numel() != array.size:
            raise ValueError(f"{key}: the graph's {array.shape} does not fit the network")
        out[key] = torch.from_numpy(np.array(array, np.float32)).reshape(target[key].shape)
    return out


def _model_json(path: Path, module: str) -> dict:
    """The model.json beside an SR graph (its training record), or {}."""
    meta = path.with_name("model.json")
    if module != "sr" or not meta.is_file():
        return {}
    try:
        return ModelConfig.from_json(meta.read_text()).to_dict()
    except (OSError, ModelConfigError):
        return {}


def graph_network(
    path: Path, groups: int = 8, tol: float = TOL
) -> tuple[str, list[AOPNet | SRNet], torch.nn.Module, float]:
    """The module, the networks (one, or an ensemble's members) and the whole function of an exported graph (the
    members' :class:`~training.model.Ensemble`, inside a :class:`~training.model.MirrorAverage` where the graph
    averages its input's mirror image), checked against the graph on random inputs: the largest difference, at most
    ``tol``."""
    model = onnx.load(str(path))
    count = _heads(model)[1]
    nets: list[AOPNet | SRNet] = []
    for k in range(count) if count else [None]:
        module, config = graph_config(model, groups, k)
        net = build(module, config)
        net.load_state_dict(state_dict_from_graph(model, net, k))
        net.eval()
        nets.append(net)
    whole = Ensemble(nets).eval() if count else nets[0]
    if mirror_concat(model) is not None:  # its network runs on the input and its mirror
        whole = MirrorAverage(whole).eval()
    diff = parity(path, whole, module, random_inputs(config.resolution))
    if diff > tol:
        raise ValueError(f"the rebuilt network is {diff:.2e} off the graph (tolerance {tol:g}; --groups?)")
    return module, nets, whole, diff


def random_inputs(r: int) -> dict[str, np.ndarray]:
    """Four random masks, AO maps, light maps, cards and camera inputs at R = ``r`` (every graph input of the
    contract)."""
    rng = np.random.default_rng(0)
    mask = (rng.random((4, 1, r, r)) > 0.5).astype(np.float32)
    elm = rng.random((4, 16, 32)).astype(np.float32)
    camera = np.array([[0.5, 1.2], [-0.2, 1.0], [0.9, 1.5], [0.3, 1.3]], np.float32)
    return {
        "mask": mask,
        "ao": rng.random(mask.shape, np.float32),
        "elm": elm / elm.max(),
        "card": mask * 0.5,
        "camera": camera,
    }


def rebuild(path: Path, groups: int = 8, tol: float = TOL, member: int | None = None) -> tuple[torch.nn.Module, dict]:
    """The network of an exported graph (``member`` of an ensemble graph) and a checkpoint dict that
    ``training.train --init-from`` accepts. An ensemble is checked whole: every member rebuilt, their mean against
    the graph."""
    weights_prefix(onnx.load(str(path)), member)  # refuses a missing or needless --member
    module, nets, whole, diff = graph_network(path, groups, tol)
    net = nets[member or 0]
    meta = _model_json(path, module)
    ck = {
        "model": net.state_dict(),
        "step": 0,
        "samples": 0,
        "module": module,
        "target": "ao" if module == "aop" else "shadow",  # what training.train records (an SR's by default)
        "unet": net.config.to_dict(),
        "rebuilt_from": str(path),
        "parity": diff,
        "training": meta.get("sr_training"),
        # the training options the exporter reads (training.model_export: the card's light maps and blur)
        "args": {
            "lights": "mix" if meta.get("lights", "").startswith(MIX_RECORD) else "table1",
            "card_blur": meta.get("card_blur", 0.0),
        },
        "mirror_average": isinstance(whole, MirrorAverage),
        "member": member,
    }
    return net, ck


def reexport(path: Path, out: Path, groups: int = 8, tol: float = TOL) -> float:
    """Write the function of an exported graph again to ``out``, in :mod:`training.export`'s current form (a graph
    from an earlier exporter gets today's faster GroupNorms); returns the largest difference between the two
    graphs on random inputs, at most ``tol``."""
    module, nets, whole, _ = graph_network(path, groups, tol)
    export_graph(whole, module, nets[0].config.resolution, out)
    old, new = session(path), session(out)
    x = random_inputs(nets[0].config.resolution)
    feeds = {i.name: x[i.name] for i in old.get_inputs()}
    diff = float(np.abs(np.asarray(new.run(None, feeds)[0]) - np.asarray(old.run(None, feeds)[0])).max())
    if diff > tol:
        raise ValueError(f"the re-exported graph is {diff:.2e} off the graph (tolerance {tol:g})")
    return diff
