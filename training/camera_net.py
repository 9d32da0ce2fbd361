"""The camera estimator: its network, data, training loop, graph and installation into a model folder.

A small CNN reads a view's horizon row and focal length from its mask in the engine's canonical framing
(:mod:`ssn_engine.methods.camera_estimate`). The horizon is read as a distribution over bins (cross-entropy on soft
labels) and the graph returns its median: where the silhouette leaves the pitch ambiguous a regression is pulled to
the middle camera by an amount that varies from run to run, while the median of a classifier's distribution stays
with the likelier camera. The graph also averages the mask with its mirror image. ``python -m
training.camera_estimator`` is the command.
"""

from __future__ import annotations

import argparse
import dataclasses
import json
import shutil
import time
from pathlib import Path

import numpy as np
import onnx
import torch
import torch.nn.functional as F
from onnx import numpy_helper
from torch import nn

from ssn_engine.camera import TOP_MARGIN
from ssn_engine.methods.camera_estimate import INPUT, canonical_input, to_canonical
from ssn_engine.model_config import ModelConfig

from .data.camera_views import KIND_NAMES, load
from .graph_weights import fitted, folded_constants
from .model_card import put_section

EDGES = np.linspace(-0.9, 0.4, 27)  # horizon bins, rows over N of the canonical frame (data: -0.83 to 0.31)
LABEL_SIGMA = 0.04  # the soft labels' spread, over N
FOCAL_MEAN, FOCAL_STD = 1.3, 0.35  # focal length over N in the canonical frame (data: median 1.25)


def examples(
    roots: Path | list[Path], split: str, sharp: bool = False
) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    """Inputs (n, INPUT, INPUT), targets (n, 2) (canonical horizon row and focal length over N), pitches (n,) and
    kinds (n,; indices into ``training.heights.KIND_NAMES``, -1 unknown) of a split's views in one or more
    ``training.heights make`` or ``training.surface make`` folders (every ``<split>*.npz``: the dataset's views,
    any others drawn with ``heights make --view-seed``, the surface sets' other shapes): from the
    128-pixel masks scaled up, as the shipped estimator was trained, or (``sharp``) the inputs ``make`` writes from
    the masks at N = 256, as sharp as the engine's."""
    roots = [roots] if isinstance(roots, Path) else roots
    paths = sorted(p for root in roots for p in root.glob(f"{split}*.npz"))
    if not paths:
        where = ", ".join(map(str, roots))
        raise SystemExit(f"no {split}*.npz in {where}: make them with `python -m training.heights make`")
    data = load(paths)
    if sharp:
        if "estimator" not in data:
            raise SystemExit(f"--sharp-input: some {split}*.npz predate it; make them again with `heights make`")
        x = data["estimator"].astype(np.float32) / 255
        return x, data["estimator_camera"].astype(np.float32), data["pitch"], data["kind"]
    seen = data["mask"].reshape(len(data["mask"]), -1).max(1) > 0  # a surface set's speck of a view may bin to none
    data = {k: v[seen] for k, v in data.items()}
    n = data["mask"].shape[-1]
    xs, ys = [], []
    for mask, camera in zip(data["mask"], data["camera"], strict=True):
        x, framing = canonical_input(mask.astype(np.float32))
        xs.append(x)
        ys.append(np.array(to_canonical(tuple(camera), framing)) / n)
    return np.stack(xs).astype(np.float32), np.stack(ys).astype(np.float32), data["pitch"], data["kind"]


def sampling_weights(kinds: np.ndarray, kind_weights: tuple[float, ...]) -> torch.Tensor:
    """Per-view sampling weights (n,) that draw each kind (object, human, animal) ``kind_weights`` times as often
    as its share of the views; a view of no recorded kind (a surface set's) once."""
    return torch.tensor(np.where(kinds < 0, 1.0, np.asarray(kind_weights, np.float64)[np.maximum(kinds, 0)]))


def _block(cin: int, cout: int) -> nn.Sequential:
    return nn.Sequential(
        nn.Conv2d(cin, cout, 3, padding=1),
        nn.GroupNorm(8, cout),
        nn.SiLU(),
        nn.Conv2d(cout, cout, 3, padding=1),
        nn.GroupNorm(8, cout),
        nn.SiLU(),
        nn.MaxPool2d(2),
    )


class CameraNet(nn.Module):
    """Five convolution blocks (64 -> 2 pixels; the mask and a row coordinate in), two dense layers out: logits
    over the horizon bins and the standardised focal length."""

    rows: torch.Tensor  # (1, 1, INPUT, INPUT) row coordinates in [-1, 1], a second input channel
    edges: torch.Tensor  # the horizon bins' edges, over N

    def __init__(self, width: int = 32) -> None:
        super().__init__()
        w = width
        chans = [2, w, 2 * w, 3 * w, 4 * w, 4 * w]
        self.features = nn.Sequential(*[_block(a, b) for a, b in zip(chans, chans[1:], strict=False)])
        side = INPUT // 32
        self.head = nn.Sequential(
            nn.Flatten(), nn.Linear(4 * w * side * side, 256), nn.SiLU(), nn.Dropout(0.3), nn.Linear(256, len(EDGES))
        )
        rows = torch.linspace(-1, 1, INPUT).view(1, 1, INPUT, 1).expand(1, 1, INPUT, INPUT).clone()
        self.register_buffer("rows", rows, persistent=False)
        self.register_buffer("edges", torch.tensor(EDGES, dtype=torch.float32), persistent=False)

    def raw(self, x: torch.Tensor) -> torch.Tensor:
        """(b, K + 1): horizon-bin logits and the standardised focal length."""
        return self.head(self.features(torch.cat([x, torch.zeros_like(x) + self.rows], 1)))

    def forward(self, x: torch.Tensor) -> torch.Tensor:
        """(b, 2): the horizon distribution's median and the focal length, over N, mask and mirror averaged."""
        out = 0.5 * (self.raw(x) + self.raw(torch.flip(x, [3])))
        p = torch.softmax(out[:, :-1], 1)
        cdf = torch.cumsum(p, 1)
        k = (cdf < 0.5).sum(1, keepdim=True).clamp(max=p.shape[1] - 1)  # the bin that holds the median
        below = torch.gather(cdf, 1, k) - torch.gather(p, 1, k)
        width = self.edges[1] - self.edges[0]
        horizon = self.edges[0] + (k.float() + (0.5 - below) / torch.gather(p, 1, k).clamp(min=1e-6)) * width
        return torch.cat([horizon, out[:, -1:] * FOCAL_STD + FOCAL_MEAN], 1)


def soft_labels(horizon: torch.Tensor) -> torch.Tensor:
    """(b, K) Gaussian soft labels over the bins for horizons (b,) over N."""
    centres = torch.tensor(0.5 * (EDGES[:-1] + EDGES[1:]), dtype=torch.float32, device=horizon.device)
    w = torch.exp(-0.5 * ((horizon[:, None] - centres[None]) / LABEL_SIGMA) ** 2)
    return w / w.sum(1, keepdim=True).clamp(min=1e-12)


def jittered(x: torch.Tensor, y: torch.Tensor, generator: torch.Generator) -> tuple[torch.Tensor, torch.Tensor]:
    """Masks (b, 1, S, S) scaled by 0.9 to 1.1 about the canonical top centre and shifted sideways by up to
    3 % of the frame, with their targets (b, 2; horizon row and focal length over N) moved to match: the
    camera is the same, seen a little closer or further."""
    b = len(x)
    k = 0.9 + 0.2 * torch.rand(b, generator=generator, device=x.device)
    dx = 0.06 * (torch.rand(b, generator=generator, device=x.device) - 0.5)
    top = round(TOP_MARGIN * INPUT) / INPUT
    ay = 2 * top - 1  # the top row in affine_grid's [-1, 1] coordinates
    theta = torch.zeros(b, 2, 3, device=x.device)
    theta[:, 0, 0] = theta[:, 1, 1] = 1 / k
    theta[:, 0, 2] = -dx
    theta[:, 1, 2] = ay * (1 - 1 / k)
    grid = F.affine_grid(theta, list(x.shape), align_corners=False)
    moved = F.grid_sample(x, grid, align_corners=False)
    return moved, torch.stack([top + (y[:, 0] - top) * k, y[:, 1] * k], dim=1)


def loss_of(net: CameraNet, x: torch.Tensor, y: torch.Tensor) -> torch.Tensor:
    out = net.raw(x)
    horizon = -(soft_labels(y[:, 0]) * F.log_softmax(out[:, :-1], 1)).sum(1).mean()
    return horizon + F.smooth_l1_loss(out[:, -1], (y[:, 1] - FOCAL_MEAN) / FOCAL_STD)


def errors_by_group(pred: np.ndarray, truth: np.ndarray, pitches: np.ndarray, kinds: np.ndarray, n: int = 256) -> dict:
    """Median absolute errors in frame pixels (N = n) of the horizon row and focal length: all views, the paper's
    pitches 0, 15 and 30 (continuous pitches within 2.5 degrees of them) and each kind of shape."""
    groups = [("all", np.ones(len(pitches), bool))]
    groups += [(f"pitch {p}", np.abs(pitches - p) < 2.5) for p in (0, 15, 30)]
    groups += [(f"{name}s", kinds == k) for k, name in enumerate(KIND_NAMES)]
    out = {}
    for name, keep in groups:
        err = np.abs(pred[keep] - truth[keep]) * n
        out[name] = {
            "views": int(keep.sum()),
            "horizon_px": float(np.median(err[:, 0])) if keep.any() else float("nan"),
            "focal_px": float(np.median(err[:, 1])) if keep.any() else float("nan"),
        }
    return out


def weights_from_graph(path: Path, net: CameraNet) -> dict[str, torch.Tensor]:
    """``net``'s state dict with the weights of an exported estimator graph: parameters by name, and each
    GroupNorm's weight and bias from the two anonymous constants the exporter folded them into, in the order the
    forward pass uses them (a shipped estimator fine-tunes without its run)."""
    inits = onnx.load(str(path)).graph.initializer
    target = net.state_dict()
    named = {i.name: numpy_helper.to_array(i) for i in inits if i.name in target}
    try:
        return fitted(target, named, folded_constants(inits, lambda name: name in target))
    except ValueError as exc:
        raise SystemExit(f"{path}: {exc}") from None


def export(net: CameraNet, path: Path) -> None:
    """Write the estimator graph ("mask" [b, 1, INPUT, INPUT] -> "camera" [b, 2])."""
    torch.onnx.export(
        net.cpu().eval(),
        (torch.zeros(1, 1, INPUT, INPUT),),
        str(path),
        input_names=["mask"],
        output_names=["camera"],
        dynamic_axes={"mask": {0: "b"}, "camera": {0: "b"}},
        opset_version=17,
        dynamo=False,
    )


def predict(net: CameraNet, x: np.ndarray) -> np.ndarray:
    net.eval()
    device = next(net.parameters()).device
    with torch.no_grad():
        batches = [torch.from_numpy(x[i : i + 256, None]).to(device) for i in range(0, len(x), 256)]
        return np.concatenate([net(b).cpu().numpy() for b in batches])


EXAMPLE_KEYS = ("x", "y", "pitch", "kind")


def write_examples(roots: list[Path], path: Path, sharp: bool = False) -> None:
    """Both splits' examples in one compressed file (inputs as 8-bit), small enough to travel to a GPU machine."""
    parts = {}
    for split in ("train", "val"):
        for key, value in zip(EXAMPLE_KEYS, examples(roots, split, sharp), strict=True):
            parts[f"{split}_{key}"] = np.round(value * 255).astype(np.uint8) if key == "x" else value
    np.savez_compressed(path, **parts)
    print(f"{len(parts['train_x'])} train and {len(parts['val_x'])} val views -> {path}")


def read_examples(args: argparse.Namespace, split: str) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    """:func:`examples` of a split, from ``--examples`` (a :func:`write_examples` file) where given."""
    if not args.examples:
        return examples(args.data, split, args.sharp_input)
    with np.load(args.examples) as data:
        x, y, pitch, kind = (data[f"{split}_{key}"] for key in EXAMPLE_KEYS)
    return x.astype(np.float32) / 255, y, pitch, kind


def train(args: argparse.Namespace) -> None:
    torch.manual_seed(args.seed)
    torch.set_num_threads(args.threads)
    device = torch.device(args.device)
    t0 = time.monotonic()
    x, y, _, kinds = read_examples(args, "train")
    xv, yv, pv, kv = read_examples(args, "val")
    weights = sampling_weights(kinds, args.kind_weights).to(device)
    print(f"{len(x)} train and {len(xv)} val views read in {time.monotonic() - t0:.0f} s", flush=True)
    net = CameraNet(args.width)
    if args.init_from:
        net.load_state_dict(weights_from_graph(Path(args.init_from), net))
    net.to(device)
    opt = torch.optim.AdamW(net.parameters(), lr=args.lr, weight_decay=1e-4)
    xt, yt = torch.from_numpy(x[:, None]).to(device), torch.from_numpy(y).to(device)
    generator = torch.Generator(device).manual_seed(args.seed)
    out = Path(args.out)
    out.mkdir(parents=True, exist_ok=True)
    history, best, best_state, step, start = [], float("inf"), None, 0, time.monotonic()
    budget = args.minutes * 60
    while (elapsed := time.monotonic() - start) < budget:
        for group in opt.param_groups:  # linear decay over the time budget
            group["lr"] = args.lr * max(0.02, 1 - elapsed / budget)
        net.train()
        idx = torch.multinomial(weights, args.batch, replacement=True, generator=generator)
        xb, yb = jittered(xt[idx], yt[idx], generator)
        flip = torch.rand(len(xb), generator=generator, device=device) < 0.5  # mirrored: the same camera
        xb = torch.where(flip[:, None, None, None], torch.flip(xb, [3]), xb)
        loss = loss_of(net, xb, yb)
        opt.zero_grad()
        loss.backward()
        opt.step()
        step += 1
        if step % args.val_every == 0:
            val = errors_by_group(predict(net, xv), yv, pv, kv)["all"]
            history.append({"step": step, "minutes": round(elapsed / 60, 1), "loss": loss.item(), **val})
            print(json.dumps(history[-1]), flush=True)
            score = val["horizon_px"] + 0.5 * val["focal_px"]
            if score < best:  # the validation split picks the step (the test split stays unseen)
                best, best_state = score, {k: v.detach().cpu().clone() for k, v in net.state_dict().items()}
                torch.save(best_state, out / "camera.pt")
    if best_state is None:
        raise SystemExit("--minutes too short for one validation; nothing to export")
    net.cpu().load_state_dict(best_state)
    report = errors_by_group(predict(net, xv), yv, pv, kv)
    export(net, out / "camera.onnx")
    summary = {
        "val": report,
        "best_step": min(history, key=lambda h: h["horizon_px"] + 0.5 * h["focal_px"])["step"],
        "steps": step,
        "train_views": len(x),
        "init_from": Path(args.init_from).name if args.init_from else None,
        "kind_weights": list(args.kind_weights),
        "minutes": round((time.monotonic() - start) / 60, 1),
        "device": torch.cuda.get_device_name(device) if device.type == "cuda" else "cpu",
        "history": history,
    }
    (out / "camera.json").write_text(json.dumps(summary, indent=1))
    print(json.dumps(report, indent=1))


CARD_SECTION = "## Camera estimator"


def install(run: Path, models: Path) -> None:
    """Install a trained estimator (``run``: camera.onnx and camera.json) into a model folder: the graph, the
    ``camera`` entry of model.json and a section of MODEL_CARD.md."""
    summary = json.loads((run / "camera.json").read_text())
    shutil.copy(run / "camera.onnx", models / "camera.onnx")
    meta_path = models / "model.json"
    config = ModelConfig.from_json(meta_path.read_text())
    val = summary["val"]
    weights = summary.get("kind_weights", [1.0, 1.0, 1.0])
    device = summary.get("device", "cpu")
    machine = "this project's 2-core CPU build machine" if device == "cpu" else f"one {device} GPU"
    drawn = "" if weights == [1.0, 1.0, 1.0] else f", objects, people and animals drawn {weights} times their share"
    camera_training = (
        f"{summary['train_views']} train views of both camera sets (mirrored and rescaled at random{drawn}), "
        f"{summary['steps']} steps in {summary['minutes']} minutes on {machine}, the "
        f"step with the lowest validation error kept ({summary['best_step']}); validation median errors: horizon "
        f"{val['all']['horizon_px']:.1f} px, focal length {val['all']['focal_px']:.1f} px (canonical frame, N = 256)"
    )
    if summary.get("init_from") and config.camera_training:  # a fine-tune of the installed estimator
        camera_training = f"{config.camera_training}; then fine-tuned on {camera_training}"
    meta_path.write_text(dataclasses.replace(config, camera="camera.onnx", camera_training=camera_training).to_json())
    rows = "\n".join(
        f"| {name} | {r['views']} | {r['horizon_px']:.1f} | {r['focal_px']:.1f} |"
        for name, r in val.items()
        if r["views"]
    )
    section = (
        f"{CARD_SECTION}\n\n"
        "`camera.onnx` reads the camera input (horizon row, focal length) from the mask for blind calls "
        "(`ssn_engine.methods.camera_estimate`); the card the SR refines and the long shadow beyond the frame are "
        f"traced with it. Trained by `python -m training.camera_estimator` on {camera_training}.\n\n"
        "| validation views (pitch: within 2.5 degrees) | views | median horizon error (px) | median focal length "
        "error (px) |\n"
        f"|---|---:|---:|---:|\n{rows}\n\n"
    )
    put_section(models / "MODEL_CARD.md", CARD_SECTION, section)
    print(f"installed {run / 'camera.onnx'} into {models}")
