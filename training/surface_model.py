"""The surface model's training and export: mask and camera input -> each pixel's pixel height.

The network is the AOP's U-Net taking the camera input (:class:`training.model.unet.AOPNet`, ``camera=True``),
wider, its output the pixel height in frames (rows / R) of :mod:`training.data.surface_views`, and with
``--depth`` a second channel, the depth (the visible surface's pixel height less the far surface's). Loss: L1 on
the covered pixels, plus L1 on the differences to the right and below within them (so that a leg in front of a
body keeps its step), summed over the channels. Mirrored half of the time (a pixel height does not change in a
mirror). Trained for a fixed time, the learning rate falling along a cosine over it; scored on the validation
split every ``VAL_EVERY`` steps (mean absolute error in rows of R, by pitch).
"""

from __future__ import annotations

import dataclasses
import json
import math
import shutil
import time
from pathlib import Path

import numpy as np
import torch

from ssn_engine.model_config import ModelConfig

from .data.surface_views import R, load
from .graph_weights import rebuild
from .model_card import put_section
from .model.mirror import MirrorAverage
from .model.unet import AOPNet, UNetConfig
from .onnx_graphs import export_graph, half_weights, session

WIDTHS = (12, 24, 48, 96, 160, 256)
VAL_EVERY = 500
GRAD_WEIGHT = 1.0
DEPTH_START = 0.02  # frames: a new depth channel's first reading, 2.5 rows of R (most pixels' depths are a few rows)
GROUPS = 4  # the U-Net's GroupNorm groups
CARD_SECTION = "## Surface model"
SCORES_MARK = "; validation mean absolute error"  # in an installed record: where its stages end and its scores begin
SECOND = "surface_second.onnx"  # a second surface graph kept by ``install --second``
PAIR_MARK = "; each pixel's height the higher of this reading and"  # in a record: where the second's begins


def build(widths: tuple[int, ...] = WIDTHS, outputs: int = 1) -> AOPNet:
    """The untrained surface network: ``outputs`` 1 (the pixel height) or 2 (and the depth)."""
    return AOPNet(UNetConfig(widths=widths, groups=GROUPS, resolution=R, camera=True, outputs=outputs))


def with_depth(net: AOPNet) -> AOPNet:
    """``net`` reading the depth as well: a one-output network given a second output channel whose reading starts
    at ``DEPTH_START`` everywhere (its first channel unchanged); a two-output one as it is."""
    if net.config.outputs == 2:
        return net
    wider = AOPNet(dataclasses.replace(net.config, outputs=2))
    state = net.state_dict()
    wider.load_state_dict({k: v for k, v in state.items() if not k.startswith("unet.head.")}, strict=False)
    weight = torch.zeros_like(wider.unet.head.weight)
    weight[:1] = state["unet.head.weight"]
    bias = torch.tensor([float(state["unet.head.bias"][0]), DEPTH_START])
    wider.unet.head.load_state_dict({"weight": weight, "bias": bias})
    return wider


def loss_terms(
    pred: torch.Tensor, target: torch.Tensor, mask: torch.Tensor, depth_weight: float = 0.0
) -> tuple[torch.Tensor, torch.Tensor]:
    """Mean L1 of the height (and the depth) over the covered pixels, and of its differences to the right and below
    over pairs of covered pixels, each summed over the channels. ``depth_weight`` (rows of R; 0: a plain mean): the
    depth's L1 a mean weighted by 1 + the true depth / ``depth_weight`` (most pixels are shallow, and a plain mean
    may read a deep body, whose outline a shallow one could also have, too shallow)."""
    n = mask.sum().clamp(min=1.0)
    err = (pred - target).abs() * mask
    l1 = err[:, :1].sum() / n
    if pred.shape[1] == 2:
        w = (1.0 + target[:, 1:] * (R / depth_weight)) * mask if depth_weight > 0 else mask
        l1 = l1 + (err[:, 1:] * w).sum() / w.sum().clamp(min=1.0)
    grad = pred.new_zeros(())
    for dim in (-1, -2):
        pair = mask.narrow(dim, 1, R - 1) * mask.narrow(dim, 0, R - 1)
        dp = pred.diff(dim=dim) - target.diff(dim=dim)
        grad = grad + (dp.abs() * pair).sum() / pair.sum().clamp(min=1.0)
    return l1, grad


def _tensors(data: dict[str, np.ndarray], device: str, outputs: int) -> tuple[torch.Tensor, torch.Tensor, torch.Tensor]:
    """Masks (n, 1, R, R) uint8, targets (n, ``outputs``, R, R) float16 in rows of R (the pixel height, and the
    depth), cameras (n, 2): kept small, each batch made float by :func:`_batch`."""
    target = np.stack([data["height"], data["depth"]][:outputs], axis=1)
    return (
        torch.from_numpy(data["mask"][:, None]).to(device),
        torch.from_numpy(target).to(device),
        torch.from_numpy(data["camera"].astype(np.float32)).to(device),
    )


def _batch(mask: torch.Tensor, target: torch.Tensor, idx: torch.Tensor | slice) -> tuple[torch.Tensor, torch.Tensor]:
    """Views ``idx`` of :func:`_tensors`' masks and targets, float32, the targets in frames."""
    return mask[idx].float(), target[idx].float() / R


def evaluate(net: AOPNet, data: dict[str, np.ndarray], device: str, batch: int = 256) -> dict[str, float]:
    """Mean absolute error (rows of R) of the pixel height over covered pixels, all views and by pitch (0-10,
    10-20, 20+ degrees); a network reading the depth: its error too (``depth``)."""
    outputs = net.config.outputs
    mask, target, camera = _tensors(data, device, outputs)
    err, count = [], []
    net.eval()
    with torch.no_grad():
        for i in range(0, len(mask), batch):
            m, t = _batch(mask, target, slice(i, i + batch))
            pred = net(m, camera[i : i + batch]).float()
            err.append(((pred - t).abs() * m).sum(dim=(2, 3)).cpu().numpy() * R)
            count.append(m.sum(dim=(1, 2, 3)).cpu().numpy())
    net.train()
    e, c = np.concatenate(err), np.concatenate(count)
    pitch = data["pitch"]
    out = {"mae": float(e[:, 0].sum() / c.sum())}
    if outputs == 2:
        out["depth"] = float(e[:, 1].sum() / c.sum())
    e = e[:, 0]
    for name, lo, hi in (("pitch 0-10", -1, 10), ("pitch 10-20", 10, 20), ("pitch 20+", 20, 90)):
        sel = (pitch >= lo) & (pitch < hi)
        if sel.any():
            out[name] = float(e[sel].sum() / c[sel].sum())
    return out


def train(
    data: Path,
    sets: list[Path],
    run: Path,
    minutes: float,
    batch: int,
    lr: float,
    device: str,
    seed: int,
    widths: tuple[int, ...] = WIDTHS,
    init: Path | None = None,
    resume: bool = False,
    depth: bool = False,
    depth_weight: float = 0.0,
) -> None:
    """Train on the views of ``sets`` (:func:`training.data.surface_views.make` files) for ``minutes``, scoring
    ``data``/val.npz; writes ``run``/last.pt (every ``VAL_EVERY`` steps) and ``run``/log.jsonl. ``init``: a
    checkpoint or an installed graph to go on from (its widths, not ``widths``). ``resume``: go on with the run
    ``run``/last.pt was saved by (its network, optimiser, step and time spent: the schedule continues where it
    stopped, so a run cut short by the end of a session finishes as if it had not been). ``depth``: read the depth
    too (a second output: :func:`with_depth` of ``init``'s network), its loss weighted by ``depth_weight``
    (:func:`loss_terms`)."""
    torch.manual_seed(seed)
    run.mkdir(parents=True, exist_ok=True)
    val_set = load([data / "val.npz"])
    state = torch.load(run / "last.pt", map_location="cpu", weights_only=True) if resume else None
    if state is not None:
        net, history = _network(state), state["history"][:-1]  # its last stage is this one
    else:
        net, history = (build(widths, 2 if depth else 1), []) if init is None else start_from(init)
        net = with_depth(net) if depth else net
    train_set = load(sets)
    mask, target, camera = _tensors(train_set, device, net.config.outputs)
    del train_set  # its arrays live on in the tensors, the targets stacked anew
    net = net.train().to(device)
    name = torch.cuda.get_device_name(device) if device.startswith("cuda") else "cpu"
    stage = {"views": len(mask), "batch": batch, "lr": lr, "device": name, "init": bool(init)}
    if depth_weight > 0:
        stage["depth_weight"] = depth_weight
    opt = torch.optim.AdamW(net.parameters(), lr=lr, weight_decay=1e-4)
    step, spent = 0, 0.0
    if state is not None:
        opt.load_state_dict(state["optimizer"])
        step, spent, stage = state["step"], state["seconds"], state["history"][-1] | {"views": len(mask)}
    rng = np.random.default_rng([seed, step])  # a resumed run draws other batches than its start did
    cuda = device.startswith("cuda")
    budget, start = minutes * 60.0, time.time() - spent
    log = (run / "log.jsonl").open("a" if state is not None else "w")
    print(f"{len(mask)} training views, {len(val_set['mask'])} validation views, from step {step}", flush=True)

    def save(row: dict) -> None:
        stages = [*history, {**stage, "steps": step, "minutes": row["seconds"] / 60}]
        _save(
            net, run / "last.pt", stages, row, {"step": step, "seconds": row["seconds"], "optimizer": opt.state_dict()}
        )

    while True:
        done = (time.time() - start) / budget
        if done >= 1.0:
            break
        for group in opt.param_groups:
            group["lr"] = lr * min(1.0, (step + 1) / 200) * 0.5 * (1.0 + math.cos(math.pi * done))
        idx = torch.from_numpy(rng.integers(0, len(mask), batch)).to(device)
        (m, t), c = _batch(mask, target, idx), camera[idx]
        if rng.random() < 0.5:
            m, t = m.flip(-1), t.flip(-1)
        with torch.autocast("cuda", dtype=torch.bfloat16, enabled=cuda):
            pred = net(m, c)
        l1, grad = loss_terms(pred.float(), t, m, depth_weight)
        loss = l1 + GRAD_WEIGHT * grad
        opt.zero_grad(set_to_none=True)
        loss.backward()
        opt.step()
        step += 1
        if step % VAL_EVERY == 0:
            row = {"step": step, "seconds": round(time.time() - start, 1), "l1": l1.item(), "grad": grad.item()}
            row.update({f"val {k}": v for k, v in evaluate(net, val_set, device).items()})
            log.write(json.dumps(row) + "\n")
            log.flush()
            print(row, flush=True)
            save(row)
    row = {"step": step, "seconds": round(time.time() - start, 1)}
    row.update({f"val {k}": v for k, v in evaluate(net, val_set, device).items()})
    log.write(json.dumps(row) + "\n")
    log.close()
    print(row, flush=True)
    save(row)


def start_from(init: Path) -> tuple[AOPNet, list]:
    """The network to go on from and its training stages: a :func:`train` checkpoint's, or an installed graph's
    (``surface.onnx``, rebuilt from its weights where its runs are gone; its stages the ``surface_training`` record
    of the model.json beside it)."""
    if init.suffix != ".onnx":
        ck = torch.load(init, map_location="cpu", weights_only=True)
        return _network(ck), ck.get("history", [])
    net = rebuild(init, groups=GROUPS)[0]
    if not isinstance(net, AOPNet) or not net.config.camera:
        raise ValueError(f"{init} is not a surface graph (mask and camera in, pixel heights out)")
    meta = init.with_name("model.json")
    record = ModelConfig.from_json(meta.read_text()).surface_training if meta.is_file() else None
    return net, [_stages(record) if record else f"rebuilt from {init.name}"]


def _stages(record: str) -> str:
    """The training stages of an installed ``surface_training`` record (:func:`install`), without its widths and
    validation scores, which the record of a network trained on from it states anew."""
    stages = record.split(SCORES_MARK)[0]
    return stages.split("], ", 1)[1] if stages.startswith("widths [") else stages


def average(first: Path, second: Path, share: float, data: Path, out: Path) -> dict[str, float]:
    """A checkpoint ``out`` whose weights are ``1 - share`` of ``first``'s and ``share`` of ``second``'s (checkpoints
    or installed graphs of one network shape; a first that does not read the depth is given a depth channel first,
    as ``train --depth`` starts one: :func:`with_depth`): a fine-tuned network taken only part of the way from the
    one it started from keeps more of what that one knew. Scored on ``data``/val.npz (the scores returned); its
    stages are ``second``'s and the average."""
    if not 0.0 <= share <= 1.0:
        raise ValueError(f"share must be in [0, 1], got {share}")
    net, _ = start_from(first)
    other, history = start_from(second)
    if other.config.outputs == 2:
        net = with_depth(net)
    a, b = net.state_dict(), other.state_dict()
    if a.keys() != b.keys() or any(a[k].shape != b[k].shape for k in a):
        raise ValueError(f"{first} and {second} are networks of different shapes")
    net.load_state_dict({k: (1.0 - share) * a[k] + share * b[k] if a[k].is_floating_point() else b[k] for k in a})
    row = {f"val {k}": v for k, v in evaluate(net, load([data / "val.npz"]), "cpu").items()}
    stage = f"averaged with {first.name}: {share:g} of these weights, {1.0 - share:g} of its"
    _save(net, out, [*history, stage], row, {})
    return row


def _save(net: AOPNet, path: Path, history: list, row: dict, progress: dict) -> None:
    """The network (weights in half precision: half the bytes, precision enough), its configuration, the
    training stages that made it (``history``: views, batch, lr, device, steps, minutes each), its last
    validation scores, and where its run stands (``progress``: step, seconds spent, the optimiser's state) for
    ``train --resume``. Written beside and then moved over ``path``: a run killed while saving keeps its last."""
    state = {k: v.detach().half().cpu() for k, v in net.state_dict().items()}
    part = path.with_suffix(".part")
    torch.save({"state": state, "config": net.config.to_dict(), "history": history, "scores": row, **progress}, part)
    part.replace(path)


def load_checkpoint(path: Path) -> AOPNet:
    """The network of a :func:`train` checkpoint, in float32 on the CPU."""
    return _network(torch.load(path, map_location="cpu", weights_only=True))


def _network(ck: dict) -> AOPNet:
    """The network of a loaded :func:`train` checkpoint, in float32 on the CPU."""
    net = AOPNet(UNetConfig.from_dict(ck["config"]))
    net.load_state_dict({k: v.float() for k, v in ck["state"].items()})
    return net.eval()


def install(checkpoint: Path, models: Path, second: Path | None = None) -> float:
    """Install the checkpoint's network into a model folder: the graph ``surface.onnx`` (:func:`export`), the
    ``surface`` and ``surface_training`` entries of model.json and a section of MODEL_CARD.md; returns the
    graph's largest difference to torch. ``second``: an installed surface graph (the one this replaces, say) kept
    beside it as ``surface_second.onnx``, each pixel's height the higher of the two readings; without it a second
    graph the folder held goes."""
    kept = models / SECOND
    second_record = ""
    if second is not None:
        start_from(second)  # refuses a file that is not a surface graph
        second_record = _installed_record(second) or second.name
        if second.resolve() != kept.resolve():
            shutil.copyfile(second, kept)
    elif kept.is_file():
        kept.unlink()
    diff = export(checkpoint, models / "surface.onnx")
    ck = torch.load(checkpoint, map_location="cpu", weights_only=True)
    stages = "; then ".join(
        h
        if isinstance(h, str)
        else f"{h['steps']} steps of {h['batch']} views ({h['views']} views, learning rate {h['lr']:g}) in "
        f"{h['minutes']:.1f} minutes on {'one ' + h['device'] + ' GPU' if h['device'] != 'cpu' else 'the CPU'}"
        for h in ck["history"]
    )
    scores = ck["scores"]
    by_pitch = ", ".join(f"{k[len('val pitch ') :]}: {v:.2f}" for k, v in scores.items() if k.startswith("val pitch"))
    depth = f", of the depth {scores['val depth']:.2f}" if "val depth" in scores else ""
    training = (
        f"widths {list(ck['config']['widths'])}, {stages}{SCORES_MARK} "
        f"{scores['val mae']:.2f} rows of R = {R} (pitch {by_pitch}){depth}"
    )
    pair = f"{PAIR_MARK} {SECOND}'s ({second_record})" if second is not None else ""
    meta = models / "model.json"
    config = ModelConfig.from_json(meta.read_text())
    config = dataclasses.replace(
        config, surface="surface.onnx", surface_second=SECOND if second else None, surface_training=training + pair
    )
    meta.write_text(config.to_json())
    section = (
        f"{CARD_SECTION}\n\n`surface.onnx` reads each pixel's pixel height (how far below it the image of the ground "
        "straight below the surface it shows lies)"
        + (", and the object's depth there (that height less the far surface's)," if depth else "")
        + " from the mask and the camera input, mirror-averaged (run on the mask and on its mirror image, the two "
        "readings averaged); the hard-light tracer places each pixel's surface with it"
        + (" and ends its segment where the depth does" if depth else "")
        + " (docs/hard_light.md). Trained by `python -m training.surface` "
        f"(training/reproduce.sh, stage 7): {training}.\n\n"
        + (
            f"`{SECOND}` is a second surface graph of the same contract, each pixel's height the higher of the two "
            f'readings (docs/training.md, "The higher of two readings"): {second_record}.\n\n'
            if second is not None
            else ""
        )
    )
    put_section(models / "MODEL_CARD.md", CARD_SECTION, section)
    return diff


def _installed_record(graph: Path) -> str | None:
    """The training record of a graph installed in its folder (model.json's ``surface_training``): of its
    ``surface`` (less what the record says of a second graph), or of its ``surface_second`` (what it says of
    that); else None."""
    meta = graph.with_name("model.json")
    if not meta.is_file():
        return None
    config = ModelConfig.from_json(meta.read_text())
    record = config.surface_training or ""
    first, _, second = record.partition(f"{PAIR_MARK} {SECOND}'s (")
    if graph.name == config.surface and first:
        return first
    if graph.name == config.surface_second and second:
        return second.removesuffix(")")
    return None


def export(checkpoint: Path, out: Path) -> float:
    """Write the checkpoint's network as ONNX ("mask" [b, 1, R, R], "camera" [b, 2] -> "height" [b, C, R, R]: the
    pixel height, and for a network reading the depth the depth, frames, clamped to [0, 1]; the weights stored in
    half precision), mirror-averaged (:class:`MirrorAverage`: run on the mask and on its mirror image, the second
    reading mirrored back and the two averaged: the camera has no roll, so the mirrored scene is as likely, and
    the average is nearer the truth); returns the largest difference of onnxruntime's output to torch's."""
    net = MirrorAverage(load_checkpoint(checkpoint)).eval()
    out.parent.mkdir(parents=True, exist_ok=True)
    export_graph(net, "aop", R, out, output="height")
    half_weights(out)  # the weights were trained and kept in half precision (:func:`_save`)
    rng = np.random.default_rng(0)
    mask = (rng.random((2, 1, R, R)) > 0.5).astype(np.float32)
    camera = np.array([[0.4, 1.2], [0.7, 0.9]], np.float32)
    got = session(out).run(None, {"mask": mask, "camera": camera})[0]
    with torch.no_grad():
        ref = net(torch.from_numpy(mask), torch.from_numpy(camera)).clamp(0.0, 1.0).numpy()
    return float(np.abs(got - ref).max())
