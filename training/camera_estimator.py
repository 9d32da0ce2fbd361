"""Train the camera estimator: a small CNN that reads a view's horizon row and focal length from its mask.

``python -m training.camera_estimator --data data/ssn256 --out runs/camera`` reads every view's mask and true
camera input (``training.batches.camera_input``), puts the mask in the engine's canonical framing
(:mod:`ssn_engine.methods.camera_estimate`), trains on the train split (mirrored masks too: the camera does not
change), reports the validation split's errors by pitch, and exports ``camera.onnx`` ("mask" [b, 1, 64, 64] ->
"camera" [b, 2], horizon row and focal length over N in the canonical frame). A few minutes on two cores.
With ``--install ssn_engine/models`` it then installs the estimator into the model folder (``--epochs 0``:
install the run in ``--out`` without training).
"""

from __future__ import annotations

import argparse
import json
import shutil
import time
from pathlib import Path

import numpy as np
import torch
from torch import nn

from ssn_engine.camera import TOP_MARGIN
from ssn_engine.methods.camera_estimate import INPUT, canonical_input, to_canonical

from .batches import camera_input
from .data.store import ViewStore

DROPOUT = 0.3


def examples(store: ViewStore, split: str) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Inputs (n, INPUT, INPUT), targets (n, 2) (canonical horizon row and focal length over N) and pitches (n,)
    of a split's views."""
    n = store.meta["res"]
    xs, ys, pitches = [], [], []
    for i in store.view_ids(split):
        info = store.info(i)
        x, framing = canonical_input(store.mask(i))
        xs.append(x)
        ys.append(np.array(to_canonical(camera_input(info, n), framing)) / n)
        pitches.append(info["pitch"])
    return np.stack(xs).astype(np.float32), np.stack(ys).astype(np.float32), np.array(pitches)


class CameraNet(nn.Module):
    """Four stride-2 convolutions (64 -> 4 pixels) and two dense layers; the output de-normalised inside."""

    def __init__(self, mean: np.ndarray, std: np.ndarray, width: int = 16) -> None:
        super().__init__()
        w = width
        chans = [1, w, 2 * w, 4 * w, 8 * w]
        layers: list[nn.Module] = []
        for a, b in zip(chans, chans[1:], strict=False):
            layers += [nn.Conv2d(a, b, 3, stride=2, padding=1), nn.ReLU(), nn.Conv2d(b, b, 3, padding=1), nn.ReLU()]
        self.features = nn.Sequential(*layers)
        side = INPUT // 16
        self.head = nn.Sequential(
            nn.Flatten(), nn.Dropout(DROPOUT), nn.Linear(8 * w * side * side, 128), nn.ReLU(), nn.Linear(128, 2)
        )
        self.register_buffer("mean", torch.tensor(mean, dtype=torch.float32))
        self.register_buffer("std", torch.tensor(std, dtype=torch.float32))

    def normalised(self, x: torch.Tensor) -> torch.Tensor:
        return self.head(self.features(x))

    def forward(self, x: torch.Tensor) -> torch.Tensor:
        return self.normalised(x) * self.std + self.mean


def jittered(x: torch.Tensor, y: torch.Tensor, n: int, generator: torch.Generator) -> tuple[torch.Tensor, torch.Tensor]:
    """Masks (b, 1, S, S) scaled by 0.9 to 1.1 about the canonical top centre and shifted sideways by up to
    3 % of the frame, with their targets (b, 2; horizon row and focal length over N) moved to match: the
    camera is the same, seen a little closer or further."""
    b = len(x)
    k = 0.9 + 0.2 * torch.rand(b, generator=generator)
    dx = 0.06 * (torch.rand(b, generator=generator) - 0.5)
    top = round(TOP_MARGIN * n) / n  # the canonical top row over N (frames of n pixels)
    ay = 2 * top - 1  # ... in affine_grid's [-1, 1] coordinates
    theta = torch.zeros(b, 2, 3)
    theta[:, 0, 0] = theta[:, 1, 1] = 1 / k
    theta[:, 0, 2] = -dx
    theta[:, 1, 2] = ay * (1 - 1 / k)
    grid = nn.functional.affine_grid(theta, list(x.shape), align_corners=False)
    moved = nn.functional.grid_sample(x, grid, align_corners=False)
    y = torch.stack([top + (y[:, 0] - top) * k, y[:, 1] * k], dim=1)
    return moved, y


def errors_by_pitch(pred: np.ndarray, truth: np.ndarray, pitches: np.ndarray, n: int) -> dict:
    """Median absolute errors in frame pixels (N = n) of the horizon row and focal length, per pitch and all."""
    out = {}
    for name, keep in [("all", np.ones(len(pitches), bool))] + [
        (f"pitch {p:g}", pitches == p) for p in sorted(set(pitches))
    ]:
        err = np.abs(pred[keep] - truth[keep]) * n
        out[name] = {
            "views": int(keep.sum()),
            "horizon_px": float(np.median(err[:, 0])),
            "focal_px": float(np.median(err[:, 1])),
        }
    return out


def train(args: argparse.Namespace) -> None:
    torch.manual_seed(args.seed)
    torch.set_num_threads(args.threads)
    store = ViewStore(args.data)
    n = store.meta["res"]
    t0 = time.monotonic()
    x, y, _ = examples(store, "train")
    xv, yv, pv = examples(store, "val")
    print(f"{len(x)} train and {len(xv)} val views read in {time.monotonic() - t0:.0f} s", flush=True)
    x, y = np.concatenate([x, x[:, :, ::-1]]), np.concatenate([y, y])  # mirrored: the same camera
    mean, std = y.mean(axis=0), y.std(axis=0)
    net = CameraNet(mean, std, args.width)
    opt = torch.optim.AdamW(net.parameters(), lr=args.lr, weight_decay=1e-3)
    sched = torch.optim.lr_scheduler.CosineAnnealingLR(opt, args.epochs)
    xt, yt = torch.from_numpy(np.ascontiguousarray(x[:, None])), torch.from_numpy(y)
    mean_t, std_t = torch.from_numpy(mean), torch.from_numpy(std)
    xvt = torch.from_numpy(xv[:, None])
    generator = torch.Generator().manual_seed(args.seed)
    history, best, best_state = [], float("inf"), None
    for epoch in range(args.epochs):
        net.train()
        order = torch.randperm(len(xt), generator=generator)
        total = 0.0
        for s in range(0, len(order), args.batch):
            idx = order[s : s + args.batch]
            xb, yb = jittered(xt[idx], yt[idx], n, generator)
            loss = nn.functional.smooth_l1_loss(net.normalised(xb), (yb - mean_t) / std_t, beta=0.1)
            opt.zero_grad()
            loss.backward()
            opt.step()
            total += float(loss) * len(idx)
        sched.step()
        net.eval()
        with torch.no_grad():
            val = errors_by_pitch(net(xvt).numpy(), yv, pv, n)["all"]
        history.append({"epoch": epoch + 1, "train_loss": total / len(order), **val})
        print(json.dumps(history[-1]), flush=True)
        score = val["horizon_px"] + val["focal_px"]
        if score < best:  # the validation split picks the epoch (the test split stays unseen)
            best, best_state = score, {k: v.clone() for k, v in net.state_dict().items()}
    assert best_state is not None
    net.load_state_dict(best_state)
    net.eval()
    with torch.no_grad():
        report = errors_by_pitch(net(xvt).numpy(), yv, pv, n)
    out = Path(args.out)
    out.mkdir(parents=True, exist_ok=True)
    torch.onnx.export(
        net,
        (xvt[:1],),
        str(out / "camera.onnx"),
        input_names=["mask"],
        output_names=["camera"],
        dynamic_axes={"mask": {0: "b"}, "camera": {0: "b"}},
        opset_version=17,
        dynamo=False,
    )
    summary = {
        "val": report,
        "best_epoch": int(np.argmin([h["horizon_px"] + h["focal_px"] for h in history])) + 1,
        "train_views": len(x) // 2,
        "epochs": args.epochs,
        "seconds": round(time.monotonic() - t0),
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
    meta = json.loads(meta_path.read_text())
    val = summary["val"]
    meta["camera"] = "camera.onnx"
    meta["camera_training"] = (
        f"{summary['train_views']} train views (and their mirror images), {summary['epochs']} epochs, the epoch "
        f"with the lowest validation error kept ({summary['best_epoch']}), {summary['seconds']} s on this "
        f"project's 2-core CPU build machine; validation median errors: horizon {val['all']['horizon_px']:.1f} "
        f"px, focal length {val['all']['focal_px']:.1f} px (N = 256)"
    )
    meta_path.write_text(json.dumps(meta, indent=1) + "\n")
    rows = "\n".join(
        f"| {name} | {r['views']} | {r['horizon_px']:.1f} | {r['focal_px']:.1f} |" for name, r in val.items()
    )
    section = (
        f"{CARD_SECTION}\n\n"
        "`camera.onnx` reads the camera input (horizon row, focal length) from the mask for blind calls "
        "(`ssn_engine.methods.camera_estimate`), and the card the SR refines is traced with it. "
        f"Trained by `python -m training.camera_estimator` on {meta['camera_training']}.\n\n"
        "| validation views | views | median horizon error (px) | median focal length error (px) |\n"
        f"|---|---:|---:|---:|\n{rows}\n\n"
    )
    card_path = models / "MODEL_CARD.md"
    text = card_path.read_text()
    if CARD_SECTION in text:
        start = text.index(CARD_SECTION)
        end = text.index("## ", start + len(CARD_SECTION))
        text = text[:start] + section + text[end:]
    else:
        at = text.index("## Training data")
        text = text[:at] + section + text[at:]
    card_path.write_text(text)
    print(f"installed {run / 'camera.onnx'} into {models}")


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--data", default="data/ssn256")
    parser.add_argument("--out", default="runs/camera")
    parser.add_argument("--epochs", type=int, default=30)
    parser.add_argument("--batch", type=int, default=64)
    parser.add_argument("--lr", type=float, default=2e-3)
    parser.add_argument("--width", type=int, default=16)
    parser.add_argument("--threads", type=int, default=2)
    parser.add_argument("--seed", type=int, default=0)
    parser.add_argument("--install", help="then install the estimator into this model folder (ssn_engine/models)")
    args = parser.parse_args()
    if args.epochs > 0:
        train(args)
    if args.install:
        install(Path(args.out), Path(args.install))


if __name__ == "__main__":
    main()
