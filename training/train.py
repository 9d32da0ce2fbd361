"""Train the AOP or the SR module (paper Section 5): ``python -m training.train --module aop|sr --run runs/NAME``.

Resumable: the run directory holds ``last.pt`` (written every ``--ckpt-minutes``
and on SIGTERM/SIGINT), ``best.pt`` (lowest validation loss), ``log.csv``,
``loss.png`` and ``samples_*.png``; running the same command again resumes.
On several GPUs or machines, launch with torchrun (DistributedDataParallel):
``torchrun --nproc_per_node=4 -m training.train --module sr ...``.

Schedule: Adam, learning rate ``--lr`` (1e-3), linear warm-up over
``--warmup`` steps, then cosine decay to ``--lr-min`` at ``--steps``.
"""

from __future__ import annotations

import argparse
import csv
import json
import os
import queue
import signal
import sys
import threading
import time
from pathlib import Path

import numpy as np
import torch
from torch.nn import functional as F

from . import checkpoint
from ssn_engine.hemisphere import texel_weights

from .batches import BatchSampler, ViewCache, make_batch
from .elm import TRAIN_MIX, sample_lights, sample_mixture
from .model import UNetConfig, build
from .model.complexity import describe
from .perturb import perturb_ao
from .plots import image_grid, loss_curve
from .progress import Progress

LOG_FIELDS = ["step", "samples", "lr", "train_loss", "val_loss", "seconds", "samples_per_s"]


def parse_args(argv: list[str] | None = None) -> argparse.Namespace:
    p = argparse.ArgumentParser(prog="python -m training.train", description=__doc__.split("\n")[0])
    p.add_argument("--module", choices=["aop", "sr"], required=True)
    p.add_argument(
        "--target",
        choices=["shadow", "irradiance"],
        default="shadow",
        help="SR target: the conventions' shadow s (SSN) or raw irradiance E (Non-inv-SSN ablation)",
    )
    p.add_argument("--data", default="data/ssn128", help="dataset root (training.data.store.ViewStore)")
    p.add_argument("--run", required=True, help="run directory (checkpoints, logs)")
    p.add_argument("--resolution", type=int, default=128)
    p.add_argument("--widths", default="8,16,32,64,96,128", help="channels per U-Net stage")
    p.add_argument("--groups", type=int, default=8)
    p.add_argument("--batch", type=int, default=16, help="batch per process")
    p.add_argument("--steps", type=int, default=6000)
    p.add_argument("--lr", type=float, default=1e-3)
    p.add_argument("--lr-min", type=float, default=1e-5)
    p.add_argument("--warmup", type=int, default=100)
    p.add_argument("--seed", type=int, default=0)
    p.add_argument("--threads", type=int, default=2, help="torch CPU threads")
    p.add_argument("--cache-views", type=int, default=300, help="views kept in memory (rotating)")
    p.add_argument("--elms-per-view", type=int, default=4, help="SR: ELMs per view in a batch (AOP: 1)")
    p.add_argument("--swap-every", type=int, default=1, help="replace a cached view every this many batches")
    p.add_argument("--no-perturb", action="store_true", help="SR: feed the ground-truth AO unperturbed")
    p.add_argument(
        "--balance-kinds",
        action="store_true",
        help="draw objects, humans and animals equally often (default: in proportion to their views)",
    )
    p.add_argument(
        "--flip",
        action="store_true",
        help="mirror half of the samples left to right (frames in x, light maps in azimuth)",
    )
    p.add_argument(
        "--ao-from",
        nargs="+",
        help="SR: AOP checkpoint(s) whose predicted AO (several: their mean, as "
        "export --aop), or an exported aop.onnx graph (such as the shipped ssn_engine/models/aop.onnx), "
        "replaces the (perturbed) ground-truth AO in a fraction --ao-from-prob of the samples "
        "(the AO SR gets in use)",
    )
    p.add_argument(
        "--card",
        action="store_true",
        help="SR: geometry-guided; the geometric card's shadow for the "
        "same light map is an input and the base of the output (training.model.SRNet)",
    )
    p.add_argument(
        "--true-camera",
        type=float,
        default=0.5,
        help="SR --card: share of samples whose card is traced with the view's true camera input "
        "(the others: the conventions' default camera, as the engine assumes blind)",
    )
    p.add_argument(
        "--lights",
        choices=["table1", "mix"],
        default="table1",
        help=f"SR: light maps from the paper's Table 1, or the mixture of light families {TRAIN_MIX} (training.elm)",
    )
    p.add_argument("--ao-from-prob", type=float, default=0.5)
    p.add_argument(
        "--through-sr",
        help="AOP: train through this frozen SR checkpoint too: the loss adds "
        "--shadow-weight x the L2 of the shadow it renders from the predicted AO under random ELMs",
    )
    p.add_argument("--shadow-weight", type=float, default=1.0)
    p.add_argument("--ckpt-minutes", type=float, default=4.0)
    p.add_argument("--refresh-minutes", type=float, default=10.0, help="re-open the store (growing dataset)")
    p.add_argument("--val-every", type=int, default=250)
    p.add_argument("--val-samples", type=int, default=48)
    p.add_argument("--log-every", type=int, default=20)
    p.add_argument(
        "--max-minutes", type=float, default=0.0, help="stop (with a checkpoint) after this long; 0: no limit"
    )
    p.add_argument("--fresh", action="store_true", help="ignore an existing checkpoint in --run")
    p.add_argument(
        "--init-from",
        help="fine-tune: start a new run from this checkpoint's weights (same module, "
        "target and U-Net) with a fresh optimizer and schedule",
    )
    args = p.parse_args(argv)
    if args.through_sr and args.module != "aop":
        p.error("--through-sr trains an AOP (--module aop)")
    if (args.card or args.lights != "table1") and args.module != "sr":
        p.error("--card and --lights apply to SR (--module sr)")
    args.widths = tuple(int(w) for w in str(args.widths).split(","))
    return args


def lr_at(step: int, args: argparse.Namespace) -> float:
    """Linear warm-up, then cosine decay from ``lr`` to ``lr_min`` at ``steps``."""
    if step < args.warmup:
        return args.lr * (step + 1) / args.warmup
    t = min(1.0, (step - args.warmup) / max(1, args.steps - args.warmup))
    return args.lr_min + 0.5 * (args.lr - args.lr_min) * (1 + np.cos(np.pi * t))


def setup_distributed() -> tuple[int, int, torch.device]:
    """(rank, world size, device); initialises torch.distributed when launched by torchrun."""
    world = int(os.environ.get("WORLD_SIZE", "1"))
    rank = int(os.environ.get("RANK", "0"))
    local = int(os.environ.get("LOCAL_RANK", "0"))
    if torch.cuda.is_available():
        torch.cuda.set_device(local)
        device = torch.device("cuda", local)
    else:
        device = torch.device("cpu")
    if world > 1:
        torch.distributed.init_process_group("nccl" if device.type == "cuda" else "gloo")
    return rank, world, device


class Prefetcher:
    """Builds batches in a background thread (numpy releases the GIL) while the model trains."""

    def __init__(self, make, rng: np.random.Generator, depth: int = 2):
        self.make, self.rng = make, rng
        self.q: queue.Queue = queue.Queue(maxsize=depth)
        self.stop = False
        self.thread = threading.Thread(target=self._run, daemon=True)
        self.thread.start()

    def _run(self) -> None:
        while not self.stop:
            try:
                item = self.make(self.rng)
            except Exception as exc:  # hand the error to the consumer
                item = exc
            self.q.put(item)
            if isinstance(item, Exception):
                return

    def next(self):
        item = self.q.get()
        if isinstance(item, Exception):
            raise item
        return item

    def close(self) -> None:
        self.stop = True
        while not self.q.empty():
            self.q.get_nowait()


def to_tensors(batch, device: torch.device) -> dict[str, torch.Tensor]:
    t = lambda a: torch.from_numpy(np.ascontiguousarray(a)).to(device)
    out = {
        "mask": t(batch.mask[:, None]),
        "ao": t(batch.ao[:, None]),
        "elm": t(batch.elm),
        "target": t(batch.target[:, None]),
    }
    if batch.card is not None:
        out["card"] = t(batch.card[:, None])
    if batch.ao_pred is not None:
        out["ao_pred"] = t(batch.ao_pred[:, None])
    return out


def forward(model, module: str, x: dict[str, torch.Tensor], ao: torch.Tensor | None = None) -> torch.Tensor:
    if module == "aop":
        return model(x["mask"])
    extra = (x["card"],) if "card" in x else ()
    return model(x["mask"], x["ao"] if ao is None else ao, x["elm"], *extra)


class OnnxAOP:
    """An exported AOP graph (aop.onnx) called like the torch AOP: mask tensor (B, 1, R, R) -> AO tensor."""

    def __init__(self, path: str):
        from ssn_engine.methods.onnx_ssn import _session

        self.session = _session(Path(path), "aop")

    def __call__(self, mask: torch.Tensor) -> torch.Tensor:
        return torch.from_numpy(self.session.run(["ao"], {"mask": mask.numpy().astype(np.float32)})[0])


def load_aop(paths: list[str]):
    """The AO predictor --ao-from names, checkpoints (their ensemble) or one exported aop.onnx graph, as a
    function of masks (B, R, R) -> AO maps (B, R, R) for the view cache (each view's AO is predicted once)."""
    net = OnnxAOP(paths[0]) if len(paths) == 1 and paths[0].endswith(".onnx") else checkpoint.load_models(paths)[0]

    @torch.no_grad()
    def predict(masks: np.ndarray) -> np.ndarray:
        return net(torch.from_numpy(np.ascontiguousarray(masks[:, None], np.float32)))[:, 0].clamp(0, 1).numpy()

    return predict


def mix_predicted_ao(x: dict[str, torch.Tensor], ao: torch.Tensor, prob: float, gen: torch.Generator) -> torch.Tensor:
    """``ao`` with each sample replaced, with probability ``prob``, by the AOP's prediction ``x["ao_pred"]``."""
    use = (torch.rand(ao.shape[0], generator=gen) < prob).to(ao.device)
    if not use.any():
        return ao
    out = ao.clone()
    out[use] = x["ao_pred"][use]
    return out


def target_of(module: str, x: dict[str, torch.Tensor]) -> torch.Tensor:
    return x["ao"] if module == "aop" else x["target"]


class Objective:
    """The loss: per-pixel L2 to the module's target; for AOP with a frozen SR network (``--through-sr``), plus
    ``shadow_weight`` x the L2 of the shadow SR renders from the predicted AO, so the AO errors that cost most in
    the shadow cost most in training."""

    def __init__(self, module: str, sr_net: torch.nn.Module | None = None, shadow_weight: float = 1.0):
        self.module, self.sr, self.shadow_weight = module, sr_net, shadow_weight

    def __call__(self, pred: torch.Tensor, x: dict[str, torch.Tensor]) -> torch.Tensor:
        loss = F.mse_loss(pred, target_of(self.module, x))
        if self.sr is not None:
            shadow = self.sr(x["mask"], pred.clamp(0.0, 1.0), x["elm"])
            loss = loss + self.shadow_weight * F.mse_loss(shadow, x["target"])
        return loss


def frozen_sr(path: str, device: torch.device) -> torch.nn.Module:
    """The SR network of checkpoint ``path`` (shadow target), without gradients for its weights."""
    net, ck = checkpoint.load_model(path)
    if ck["module"] != "sr" or ck.get("target") != "shadow" or ck["unet"].get("card"):
        raise SystemExit(
            f"--through-sr needs an SR checkpoint with the shadow target and no card input; {path} is "
            f"{ck['module']}/{ck.get('target')}{' (card)' if ck['unet'].get('card') else ''}"
        )
    return net.requires_grad_(False).to(device)


def shadow_target(args: argparse.Namespace) -> str | None:
    """The light-dependent target the batches carry: SR's, or the shadow for AOP trained through SR."""
    if args.module == "sr":
        return args.target
    return "shadow" if args.through_sr else None


def build_val(store, args, weights_rows: int, run: Path | None = None):
    """A fixed validation batch (val split; the train split if val is empty). The chosen views are saved in
    ``run/val_views.json`` and reused on resume, so validation losses stay comparable while the store grows."""
    from .batches import load_view, view_key

    saved = run / "val_views.json" if run is not None else None
    lit = shadow_target(args)
    split = "val" if store.view_ids("val") else "train"
    rng = np.random.default_rng([args.seed, 7919])
    ids_by_key = {view_key(store, i): i for i in store.view_ids(None)}
    if saved is not None and saved.is_file():
        record = json.loads(saved.read_text())
        split = record["split"]
        chosen = [ids_by_key[tuple(k)] for k in record["views"] if tuple(k) in ids_by_key]
    else:
        ids = store.view_ids(split)
        chosen = [ids[j] for j in rng.choice(len(ids), size=args.val_samples, replace=len(ids) < args.val_samples)]
        if saved is not None:
            saved.write_text(json.dumps({"split": split, "views": [list(view_key(store, i)) for i in chosen]}))
    views = {}
    for i in chosen:
        k = view_key(store, i)
        if k not in views:
            views[k] = load_view(store, i, args.resolution, with_occ=lit is not None, with_card=args.card)
    vs = [views[view_key(store, i)] for i in chosen]
    rng = np.random.default_rng([args.seed, 104729])
    lights = sample_mixture(rng, len(vs), TRAIN_MIX) if args.lights == "mix" else sample_lights(rng, len(vs))
    true_camera = np.arange(len(vs)) % 2 == 1  # half of the cards with the true camera
    return make_batch(vs, lights, weights_rows, texel_weights(weights_rows), lit, true_camera), split


@torch.no_grad()
def validate(
    model, module: str, val: dict[str, torch.Tensor], objective: Objective, chunk: int = 16
) -> tuple[float, torch.Tensor]:
    """The objective on the validation batch (chunks weighted by size) and the predictions."""
    model.eval()
    preds, total = [], 0.0
    for i in range(0, val["mask"].shape[0], chunk):
        part = {k: v[i : i + chunk] for k, v in val.items()}
        preds.append(forward(model, module, part))
        total += float(objective(preds[-1], part)) * preds[-1].shape[0]
    model.train()
    return total / val["mask"].shape[0], torch.cat(preds)


def write_samples(path: Path, module: str, val: dict[str, torch.Tensor], pred: torch.Tensor, n: int = 6) -> None:
    rows = []
    for b in range(min(n, pred.shape[0])):
        m, a = val["mask"][b, 0].cpu().numpy(), val["ao"][b, 0].cpu().numpy()
        p, g = pred[b, 0].cpu().numpy(), target_of(module, val)[b, 0].cpu().numpy()
        scale = max(float(g.max()), 1e-6) if module == "sr" and g.max() > 1 else 1.0
        elm = np.kron(val["elm"][b].cpu().numpy(), np.ones((4, 4))) if module == "sr" else None
        row = [m, a] if module == "aop" else [m, a, elm]
        card = [val["card"][b, 0].cpu().numpy()] if "card" in val else []
        rows.append(row + card + [p / scale, g / scale, np.abs(p - g) / scale * 4])
    labels = (["mask", "gt ao"] if module == "aop" else ["mask", "gt ao", "elm"]) + (["card"] if "card" in val else [])
    labels += ["pred", "gt", "|err|x4"]
    image_grid(rows, path, labels, cell=112)


def read_log(path: Path) -> list[dict]:
    if not path.is_file():
        return []
    with path.open() as f:
        return list(csv.DictReader(f))


def plot_log(run: Path, title: str) -> None:
    rows = read_log(run / "log.csv")
    train = [(float(r["step"]), float(r["train_loss"])) for r in rows if r["train_loss"]]
    val = [(float(r["step"]), float(r["val_loss"])) for r in rows if r["val_loss"]]
    loss_curve({"train (per-pixel L2)": train, "val": val}, run / "loss.png", title)


def main(argv: list[str] | None = None, store=None) -> int:
    """Train; ``store`` replaces ``ViewStore(--data)`` (tests pass an in-memory stand-in)."""
    args = parse_args(argv)
    if args.module == "aop":
        args.target = "ao"
    torch.set_num_threads(args.threads)
    rank, world, device = setup_distributed()
    objective = Objective(
        args.module, frozen_sr(args.through_sr, device) if args.through_sr else None, args.shadow_weight
    )
    main_proc = rank == 0
    run = Path(args.run)
    run.mkdir(parents=True, exist_ok=True)
    torch.manual_seed(args.seed)

    from .data.store import ViewStore

    fixed_store = store is not None
    store = store if fixed_store else ViewStore(args.data)
    config = UNetConfig(widths=args.widths, groups=args.groups, resolution=args.resolution, card=args.card)
    head_bias = {"ao": 1.0, "shadow": 0.0, "irradiance": 1.0}[args.target]
    model = build(args.module, config, head_bias).to(device)
    if main_proc:
        print(describe(args.module, model, args.resolution), flush=True)
    opt = torch.optim.Adam(model.parameters(), lr=args.lr)
    step, samples, best = 0, 0, float("inf")
    ckpt_path = None if args.fresh else checkpoint.resume_path(run)

    def load_matching(path, advice: str) -> dict:
        """The checkpoint at ``path``, refused unless it holds this run's module, target and U-Net."""
        ck = checkpoint.load(path)
        if ck["module"] != args.module or ck.get("target") != args.target or ck["unet"] != config.to_dict():
            raise SystemExit(f"{path} is a {ck['module']}/{ck.get('target')} {ck['unet']} run; {advice}")
        return ck

    if ckpt_path is not None:
        ckpt = load_matching(ckpt_path, "use another --run or --fresh")
        model.load_state_dict(ckpt["model"])
        opt.load_state_dict(ckpt["optimizer"])
        step, samples, best = ckpt["step"], ckpt["samples"], ckpt.get("best_val", float("inf"))
        if main_proc:
            print(f"resumed from {ckpt_path} at step {step}", flush=True)
    elif args.init_from:
        init = load_matching(args.init_from, "it cannot initialise this run (--init-from)")
        model.load_state_dict(init["model"])
        if main_proc:
            print(f"initialised from {args.init_from} (step {init['step']})", flush=True)
    if main_proc:
        (run / "config.json").write_text(json.dumps({**vars(args), "widths": list(args.widths)}, indent=1))
    ddp = torch.nn.parallel.DistributedDataParallel(model) if world > 1 else model

    lit = shadow_target(args)
    predict_ao = load_aop(args.ao_from) if args.module == "sr" and args.ao_from else None
    cache = ViewCache(
        store,
        "train",
        args.resolution,
        max_views=100000 if lit is None else args.cache_views,
        with_occ=lit is not None,
        balance_kinds=args.balance_kinds,
        with_card=args.card,
        predict_ao=predict_ao,
    )
    # A plain AOP ignores the light, so repeating a view under several ELMs would only shrink its batch.
    sampler = BatchSampler(
        cache,
        args.batch,
        lit,
        1 if lit is None else args.elms_per_view,
        flip=args.flip,
        lights=TRAIN_MIX if args.lights == "mix" else None,
        true_camera=args.true_camera,
        swap_every=args.swap_every,
    )
    rows = store.meta["elm_rows"]
    val_batch, val_split = build_val(store, args, rows, run) if main_proc else (None, None)
    val = to_tensors(val_batch, device) if val_batch is not None else None
    if main_proc:
        print(
            f"train views: {len(cache)} (cache {args.cache_views}), val: {args.val_samples} samples from the "
            f"{val_split} split, batch {args.batch} x {world} process(es), device {device}",
            flush=True,
        )
    gen = torch.Generator().manual_seed(args.seed * 1000 + rank + step)
    pre = Prefetcher(sampler, np.random.default_rng([args.seed, rank, step]))

    stop = {"flag": False}

    def on_signal(signum, _frame):
        stop["flag"] = True

    signal.signal(signal.SIGTERM, on_signal)
    signal.signal(signal.SIGINT, on_signal)

    def save_ckpt(path: Path) -> None:
        checkpoint.save(
            path,
            {
                "model": model.state_dict(),
                "optimizer": opt.state_dict(),
                "step": step,
                "samples": samples,
                "best_val": best,
                "module": args.module,
                "target": args.target,
                "unet": config.to_dict(),
                "args": {**vars(args), "widths": list(args.widths)},
                "elm_rows": rows,
                "data": str(args.data),
            },
        )

    log_path = run / "log.csv"
    new_log = not log_path.is_file()
    log_f = log_path.open("a", newline="") if main_proc else None
    writer = csv.DictWriter(log_f, LOG_FIELDS) if log_f else None
    if writer and new_log:
        writer.writeheader()
    t_start = time.perf_counter()
    t_ckpt = t_refresh = time.perf_counter()
    old_rows = read_log(log_path) if main_proc and not new_log else []
    prior_seconds = float(old_rows[-1]["seconds"]) if old_rows else 0.0
    progress = Progress(args.steps, start=step, every=args.log_every)
    running, n_running, t_log = 0.0, 0, time.perf_counter()
    ddp.train()
    while step < args.steps and not stop["flag"]:
        lr = lr_at(step, args)
        for g in opt.param_groups:
            g["lr"] = lr
        x = to_tensors(pre.next(), device)
        ao_in = None
        if args.module == "sr" and not args.no_perturb:
            ao_in = perturb_ao(x["ao"].cpu(), gen).to(device)
        if "ao_pred" in x:
            ao_in = mix_predicted_ao(x, x["ao"] if ao_in is None else ao_in, args.ao_from_prob, gen)
        pred = forward(ddp, args.module, x, ao_in)
        loss = objective(pred, x)
        opt.zero_grad(set_to_none=True)
        loss.backward()
        opt.step()
        step += 1
        samples += args.batch * world
        running += loss.item()
        n_running += 1
        if main_proc:
            progress.update(step, f"loss {running / n_running:.5f} lr {lr:.2e}")
        do_val = main_proc and (step % args.val_every == 0 or step == args.steps)
        if main_proc and (step % args.log_every == 0 or do_val):
            row = {
                "step": step,
                "samples": samples,
                "lr": f"{lr:.3e}",
                "train_loss": f"{running / n_running:.6f}",
                "val_loss": "",
                "seconds": f"{prior_seconds + time.perf_counter() - t_start:.1f}",
                "samples_per_s": f"{n_running * args.batch * world / (time.perf_counter() - t_log):.2f}",
            }
            running, n_running, t_log = 0.0, 0, time.perf_counter()
            if do_val:
                v, vpred = validate(model, args.module, val, objective)
                row["val_loss"] = f"{v:.6f}"
                write_samples(run / "samples_latest.png", args.module, val, vpred)
                if v < best:
                    best = v
                    save_ckpt(run / checkpoint.BEST)
            writer.writerow(row)
            log_f.flush()
            if do_val:
                plot_log(run, f"{args.module.upper()} ({args.target}) {run.name}")
        if main_proc and time.perf_counter() - t_ckpt > args.ckpt_minutes * 60:
            save_ckpt(run / checkpoint.LAST)
            t_ckpt = time.perf_counter()
        if not fixed_store and time.perf_counter() - t_refresh > args.refresh_minutes * 60:
            store = ViewStore(args.data)
            pre.close()
            cache.open(store)
            pre = Prefetcher(sampler, np.random.default_rng([args.seed, rank, step]))
            t_refresh = time.perf_counter()
            if main_proc:
                print(f"\nstore re-opened: {len(cache)} train views", flush=True)
        if args.max_minutes and time.perf_counter() - t_start > args.max_minutes * 60:
            break
    pre.close()
    if main_proc:
        progress.close()
        save_ckpt(run / checkpoint.LAST)
        plot_log(run, f"{args.module.upper()} ({args.target}) {run.name}")
        print(f"stopped at step {step} ({samples} samples); checkpoint {run / checkpoint.LAST}", flush=True)
        log_f.close()
    if world > 1:
        torch.distributed.destroy_process_group()
    return 0


if __name__ == "__main__":
    sys.exit(main())
