"""The training loop of ``python -m training.train``: the network, its data, the steps, validation, logs and
checkpoints of one run (resumable; DistributedDataParallel under torchrun). :func:`run` is the entry point."""

from __future__ import annotations

import argparse
import dataclasses
import json
import os
import signal
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np
import torch

from ssn_engine.hemisphere import texel_weights
from ssn_engine.methods.geometric import GeometricCard
from ssn_engine.methods.onnx_ssn import blur_frames

from . import checkpoint
from .ao_predictors import load_aop
from .batches import BatchSampler, ViewCache, load_view, make_batch, move_blind_cameras, view_key
from .data.packed import PackedStore, is_packed
from .data.store import ViewStore
from .elm import TRAIN_MIX, sample_lights, sample_mixture
from .losses import Objective, target_of
from .model import UNetConfig, build
from .model.complexity import describe
from .perturb import perturb_ao
from .plots import image_grid
from .prefetch import BatchStream
from .run_log import Interval, RunLog, plot_log

__all__ = ["lr_at", "mix_predicted_ao", "run", "with_new_inputs"]


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


def to_tensors(batch, device: torch.device, card_blur: float = 0.0, camera: bool = False) -> dict[str, torch.Tensor]:
    """A batch's arrays as tensors on ``device``; the card's shadow blurred by ``card_blur`` pixels; ``camera``:
    with the camera inputs (a camera-taking AOP)."""
    t = lambda a: torch.from_numpy(np.ascontiguousarray(a)).to(device)
    out = {
        "mask": t(batch.mask[:, None]),
        "ao": t(batch.ao[:, None]),
        "elm": t(batch.elm),
        "target": t(batch.target[:, None]),
    }
    if batch.card is not None:
        out["card"] = t(blur_frames(batch.card, card_blur)[:, None])
    if batch.ao_pred is not None:
        out["ao_pred"] = t(batch.ao_pred[:, None])
    if camera:
        out["camera"] = t(batch.camera)
    return out


def forward(model, module: str, x: dict[str, torch.Tensor], ao: torch.Tensor | None = None) -> torch.Tensor:
    if module == "aop":
        return model(x["mask"], x["camera"]) if "camera" in x else model(x["mask"])
    extra = (x["card"],) if "card" in x else ()
    return model(x["mask"], x["ao"] if ao is None else ao, x["elm"], *extra)


def blind_error(args: argparse.Namespace) -> tuple[float, float] | None:
    """--blind-camera-error as (horizon, log focal length) scales, or None."""
    error = args.blind_camera_error
    return None if error is None else (float(error[0]), float(error[1]))


def card_method(args: argparse.Namespace) -> GeometricCard | None:
    """The card an SR --card run traces for its views (the engine's flat card at R), or None."""
    return GeometricCard(internal=args.resolution) if args.card else None


def mix_predicted_ao(x: dict[str, torch.Tensor], ao: torch.Tensor, prob: float, gen: torch.Generator) -> torch.Tensor:
    """``ao`` with each sample replaced, with probability ``prob``, by the AOP's prediction ``x["ao_pred"]``."""
    use = (torch.rand(ao.shape[0], generator=gen) < prob).to(ao.device)
    if not use.any():
        return ao
    out = ao.clone()
    out[use] = x["ao_pred"][use]
    return out


def shadow_target(args: argparse.Namespace) -> str | None:
    """The light-dependent target the batches carry: SR's (an AOP's batches carry none)."""
    return args.target if args.module == "sr" else None


def build_val(store, args, weights_rows: int, run: Path | None = None):
    """A fixed validation batch (val split; the train split if val is empty). The chosen views are saved in
    ``run/val_views.json`` and reused on resume, so validation losses stay comparable while the store grows."""
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
    card = card_method(args)
    for i in chosen:
        k = view_key(store, i)
        if k not in views:
            views[k] = load_view(
                store, i, args.resolution, lit is not None, card, None, blind_error(args), np.random.default_rng(i)
            )
    vs = [views[view_key(store, i)] for i in chosen]
    rng = np.random.default_rng([args.seed, 104729])
    lights = sample_mixture(rng, len(vs), TRAIN_MIX) if args.lights == "mix" else sample_lights(rng, len(vs))
    true_camera = np.arange(len(vs)) % 2 == 1  # half of the cards (a --camera AOP: cameras) the true one
    batch = make_batch(vs, lights, weights_rows, texel_weights(weights_rows), lit, true_camera)
    error = blind_error(args)
    if args.camera and error is not None:
        move_blind_cameras(batch, true_camera, error, rng)
    return batch, split


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


# The output conv's bias starts at the typical target (docs/training.md, "Network").
HEAD_BIAS = {"ao": 1.0, "shadow": 0.0, "irradiance": 1.0}


@dataclass
class Process:
    """This process of the run: its rank and the world size (torchrun, else 1) and its device."""

    rank: int
    world: int
    device: torch.device

    @property
    def is_main(self) -> bool:
        """Rank 0 validates, logs and checkpoints."""
        return self.rank == 0


@dataclass
class Network:
    """The module being trained, its U-Net shape and Adam optimizer, and where training stands (checkpointed).

    ``parallel`` is what the train steps call: the DistributedDataParallel wrapper, or the model itself.
    """

    model: torch.nn.Module
    config: UNetConfig
    opt: torch.optim.Optimizer
    parallel: torch.nn.Module
    step: int = 0
    samples: int = 0
    best: float = float("inf")


@dataclass
class TrainData:
    """The train split's view cache and batch sampler, the basis grid's ELM rows and rank 0's validation batch."""

    cache: ViewCache
    sampler: BatchSampler
    elm_rows: int
    val: dict[str, torch.Tensor] | None
    refreshable: bool  # the store is re-opened every --refresh-minutes (not a store handed to main, nor a packed file)


def start_process(args: argparse.Namespace) -> Process:
    """Torch's CPU threads, and this process's rank and device (DistributedDataParallel under torchrun)."""
    torch.set_num_threads(args.threads)
    return Process(*setup_distributed())


def make_objective(args: argparse.Namespace) -> Objective:
    """Per-pixel L2 to the target, plus --zncc-weight x (1 - ZNCC)."""
    return Objective(args.module, args.zncc_weight)


def open_run(args: argparse.Namespace) -> Path:
    """The run directory (created)."""
    run = Path(args.run)
    run.mkdir(parents=True, exist_ok=True)
    return run


def open_store(args: argparse.Namespace, given: Any = None) -> Any:
    """``given`` (a test's stand-in), else the ViewStore of --data as the generator has written it so far, or a
    packed file's views (``training.data.packed``)."""
    if given is not None:
        return given
    if is_packed(args.data):
        return PackedStore(args.data[0])
    return ViewStore(args.data)


def build_network(args: argparse.Namespace, proc: Process) -> Network:
    """The module's U-Net (seeded by --seed, the output bias at the typical target) and its Adam optimizer."""
    torch.manual_seed(args.seed)
    config = UNetConfig(
        widths=args.widths, groups=args.groups, resolution=args.resolution, card=args.card, camera=args.camera
    )
    model = build(args.module, config, HEAD_BIAS[args.target]).to(proc.device)
    if proc.is_main:
        print(describe(args.module, model, args.resolution), flush=True)
    return Network(model, config, torch.optim.Adam(model.parameters(), lr=args.lr), parallel=model)


def load_matching(
    path: str | Path, args: argparse.Namespace, config: UNetConfig, advice: str, camera_added: bool = False
) -> dict:
    """The checkpoint at ``path``, refused unless it holds this run's module, target and U-Net (``camera_added``:
    or that U-Net without the camera input)."""
    ck = checkpoint.load(path)
    unet = UNetConfig.from_dict(ck["unet"])  # (a checkpoint from before a field was added gets its default)
    if camera_added:
        unet = dataclasses.replace(unet, camera=True)
    if ck["module"] != args.module or ck.get("target") != args.target or unet != config:
        raise SystemExit(f"{path} is a {ck['module']}/{ck.get('target')} {ck['unet']} run; {advice}")
    return ck


def resume(net: Network, args: argparse.Namespace, path: Path, proc: Process) -> None:
    """Continue the run of ``last.pt``: weights, optimizer, step, samples and best validation loss."""
    ck = load_matching(path, args, net.config, "use another --run or --fresh")
    net.model.load_state_dict(ck["model"])
    net.opt.load_state_dict(ck["optimizer"])
    net.step, net.samples, net.best = ck["step"], ck["samples"], ck.get("best_val", float("inf"))
    if proc.is_main:
        print(f"resumed from {path} at step {net.step}", flush=True)


def init_from(net: Network, args: argparse.Namespace, proc: Process) -> None:
    """Fine-tune: a new run from --init-from's weights, with a fresh optimizer and schedule. An AOP without the
    camera input starts a --camera one: the camera channels' first weights start at zero, so the new network
    starts as the old one."""
    ck = load_matching(args.init_from, args, net.config, "it cannot initialise this run (--init-from)", args.camera)
    net.model.load_state_dict(with_new_inputs(ck["model"], net.model.state_dict()))
    if proc.is_main:
        print(f"initialised from {args.init_from} (step {ck['step']})", flush=True)


def with_new_inputs(state: dict[str, torch.Tensor], target: dict[str, torch.Tensor]) -> dict[str, torch.Tensor]:
    """``state`` with each weight that has fewer input channels (dim 1) than ``target``'s padded with zeros."""
    out = dict(state)
    for k, w in state.items():
        t = target[k]
        if w.ndim == 4 and t.shape[1] > w.shape[1] and t.shape[0] == w.shape[0]:
            out[k] = torch.cat([w, torch.zeros(w.shape[0], t.shape[1] - w.shape[1], *w.shape[2:])], dim=1)
    return out


def restore(net: Network, args: argparse.Namespace, run: Path, proc: Process) -> None:
    """Resume from the run's checkpoint (unless --fresh), else start from --init-from's weights if given."""
    path = None if args.fresh else checkpoint.resume_path(run)
    if path is not None:
        resume(net, args, path, proc)
    elif args.init_from:
        init_from(net, args, proc)


def args_record(args: argparse.Namespace) -> dict:
    """The arguments as config.json and the checkpoints keep them."""
    return {**vars(args), "widths": list(args.widths)}


def write_config(run: Path, args: argparse.Namespace, proc: Process) -> None:
    """``config.json`` of the run (rank 0)."""
    if proc.is_main:
        (run / "config.json").write_text(json.dumps(args_record(args), indent=1))


def distribute(net: Network, proc: Process) -> None:
    """Wrap the restored model in DistributedDataParallel when several processes train it."""
    if proc.world > 1:
        net.parallel = torch.nn.parallel.DistributedDataParallel(net.model)


def train_cache(args: argparse.Namespace, store: Any) -> ViewCache:
    """The train split's views at R (a plain AOP keeps them all: it needs no bases), with their bases, cards and
    the --ao-from (and --ao-from-camera) AOPs' predicted AO as the run needs them."""
    lit = shadow_target(args)
    predict_ao = load_aop(args.ao_from) if args.module == "sr" and args.ao_from else None
    predict_ao_camera = load_aop(args.ao_from_camera, camera=True) if args.ao_from_camera else None
    return ViewCache(
        store,
        "train",
        args.resolution,
        max_views=100000 if lit is None else args.cache_views,
        with_occ=lit is not None,
        balance_kinds=args.balance_kinds,
        card=card_method(args),
        predict_ao=predict_ao,
        predict_ao_camera=predict_ao_camera,
        camera_error=blind_error(args),
        seed=args.seed,
    )


def batch_sampler(args: argparse.Namespace, cache: ViewCache) -> BatchSampler:
    """Batches of --elms-per-view fresh light maps per view (Table 1 or the family mixture), mirrored with --flip."""
    lit = shadow_target(args)
    # A plain AOP ignores the light, so repeating a view under several ELMs would only shrink its batch.
    return BatchSampler(
        cache,
        args.batch,
        lit,
        1 if lit is None else args.elms_per_view,
        flip=args.flip,
        lights=TRAIN_MIX if args.lights == "mix" else None,
        true_camera=args.true_camera,
        swap_every=args.swap_every,
    )


def build_data(args: argparse.Namespace, proc: Process, store: Any, run: Path, refreshable: bool) -> TrainData:
    """Views of the store: the train split's cache and sampler, and on rank 0 the fixed validation batch."""
    cache = train_cache(args, store)
    sampler = batch_sampler(args, cache)
    rows = store.meta["elm_rows"]
    val_batch, val_split = build_val(store, args, rows, run) if proc.is_main else (None, None)
    val = to_tensors(val_batch, proc.device, args.card_blur, args.camera) if val_batch is not None else None
    if proc.is_main:
        print(
            f"train views: {len(cache)} (cache {args.cache_views}), val: {args.val_samples} samples from the "
            f"{val_split} split, batch {args.batch} x {proc.world} process(es), device {proc.device}",
            flush=True,
        )
    return TrainData(cache, sampler, rows, val, refreshable)


def stop_on_signals() -> dict[str, bool]:
    """A flag that SIGTERM and SIGINT (Ctrl-C) raise, so the run ends cleanly with a checkpoint."""
    stop = {"flag": False}

    def on_signal(signum, _frame):
        stop["flag"] = True

    signal.signal(signal.SIGTERM, on_signal)
    signal.signal(signal.SIGINT, on_signal)
    return stop


def ao_input(args: argparse.Namespace, x: dict[str, torch.Tensor], gen: torch.Generator) -> torch.Tensor | None:
    """SR's AO input: the ground truth perturbed, in a share --ao-from-prob of the samples the AOP's prediction
    instead; None: the batch's AO as it is (an AOP's)."""
    ao_in = None
    if args.module == "sr":
        ao_in = perturb_ao(x["ao"].cpu(), gen).to(x["ao"].device)
    if "ao_pred" in x:
        ao_in = mix_predicted_ao(x, x["ao"] if ao_in is None else ao_in, args.ao_from_prob, gen)
    return ao_in


def train_step(
    net: Network, module: str, objective: Objective, x: dict[str, torch.Tensor], ao: torch.Tensor | None, lr: float
) -> float:
    """One Adam step at learning rate ``lr`` on batch ``x``; the loss."""
    for g in net.opt.param_groups:
        g["lr"] = lr
    loss = objective(forward(net.parallel, module, x, ao), x)
    net.opt.zero_grad(set_to_none=True)
    loss.backward()
    net.opt.step()
    return loss.item()


def save_checkpoint(path: Path, net: Network, args: argparse.Namespace, elm_rows: int) -> None:
    """``last.pt`` or ``best.pt``: weights, optimizer, progress, and what the network is (module, target, U-Net)."""
    checkpoint.save(
        path,
        {
            "model": net.model.state_dict(),
            "optimizer": net.opt.state_dict(),
            "step": net.step,
            "samples": net.samples,
            "best_val": net.best,
            "module": args.module,
            "target": args.target,
            "unet": net.config.to_dict(),
            "args": args_record(args),
            "elm_rows": elm_rows,
            "data": [str(d) for d in args.data],
        },
    )


def loss_title(args: argparse.Namespace, run: Path) -> str:
    """The title of ``loss.png``: module, target, run and loss."""
    loss = "per-pixel L2"
    if args.zncc_weight:
        loss += f" + {args.zncc_weight:g} x (1 - ZNCC)"
    return f"{args.module.upper()} ({args.target}) {run.name}: {loss}"


def validate_and_keep_best(
    args: argparse.Namespace, run: Path, net: Network, data: TrainData, objective: Objective
) -> float:
    """The validation loss; writes ``samples_latest.png``, and ``best.pt`` at the lowest loss so far."""
    if data.val is None:
        raise RuntimeError("only rank 0 validates")
    v, pred = validate(net.model, args.module, data.val, objective)
    write_samples(run / "samples_latest.png", args.module, data.val, pred)
    if v < net.best:
        net.best = v
        save_checkpoint(run / checkpoint.BEST, net, args, data.elm_rows)
    return v


def report(
    args: argparse.Namespace, run: Path, net: Network, data: TrainData, objective: Objective, log: RunLog, lr: float
) -> None:
    """Rank 0 after a step: a log row every --log-every steps; every --val-every steps and at the end, with the
    validation loss, samples, ``best.pt`` and ``loss.png``."""
    do_val = net.step % args.val_every == 0 or net.step == args.steps
    if net.step % args.log_every and not do_val:
        return
    row = log.row(net.step, net.samples, lr)
    if do_val:
        row["val_loss"] = f"{validate_and_keep_best(args, run, net, data, objective):.6f}"
    log.write(row)
    if do_val:
        plot_log(run, loss_title(args, run))


def refresh_store(args: argparse.Namespace, data: TrainData, stream: BatchStream, step: int, proc: Process) -> None:
    """Re-open the store so the cache picks up meshes the generator finished meanwhile; restart the stream."""
    store = open_store(args)
    stream.close()
    data.cache.open(store)
    stream.start(step)
    if proc.is_main:
        print(f"\nstore re-opened: {len(data.cache)} train views", flush=True)


def train(
    args: argparse.Namespace, proc: Process, run: Path, net: Network, data: TrainData, objective: Objective
) -> None:
    """Train steps to --steps (or a stop signal, or --max-minutes): learning rate schedule, batch, Adam step;
    rank 0 logs, validates and writes ``last.pt`` every --ckpt-minutes and at the end."""
    stream = BatchStream(data.sampler, args.seed, proc.rank, net.step)
    stop = stop_on_signals()
    log = RunLog(run, proc.is_main, args.steps, net.step, args.log_every, args.batch * proc.world)
    ckpt_clock, refresh_clock = Interval(args.ckpt_minutes), Interval(args.refresh_minutes)
    net.parallel.train()
    while net.step < args.steps and not stop["flag"]:
        lr = lr_at(net.step, args)
        x = to_tensors(stream.next(), proc.device, args.card_blur, args.camera)
        loss = train_step(net, args.module, objective, x, ao_input(args, x, stream.gen), lr)
        net.step += 1
        net.samples += args.batch * proc.world
        log.add(net.step, loss, lr)
        if proc.is_main:
            report(args, run, net, data, objective, log, lr)
        if proc.is_main and ckpt_clock.due():
            save_checkpoint(run / checkpoint.LAST, net, args, data.elm_rows)
            ckpt_clock.restart()
        if data.refreshable and refresh_clock.due():
            refresh_store(args, data, stream, net.step, proc)
            refresh_clock.restart()
        if args.max_minutes and log.elapsed() > args.max_minutes * 60:
            break
    stream.close()
    if proc.is_main:
        finish_run(args, run, net, data, log)


def finish_run(args: argparse.Namespace, run: Path, net: Network, data: TrainData, log: RunLog) -> None:
    """Rank 0 at the end of a chunk: ``last.pt``, the loss plot, and where it stopped."""
    log.progress.close()
    save_checkpoint(run / checkpoint.LAST, net, args, data.elm_rows)
    plot_log(run, loss_title(args, run))
    print(f"stopped at step {net.step} ({net.samples} samples); checkpoint {run / checkpoint.LAST}", flush=True)
    log.close()


def end_process(proc: Process) -> None:
    """Leave the process group of a distributed run, all ranks together: a rank that tore its group down while
    rank 0 still wrote the run's files could abort at exit ("terminate called without an active exception")."""
    if proc.world > 1:
        torch.distributed.barrier()
        torch.distributed.destroy_process_group()


def run(args: argparse.Namespace, store: Any = None) -> None:
    """Train as ``args`` (:func:`training.train.parse_args`) asks; ``store`` replaces ``ViewStore(--data)`` (tests
    pass an in-memory stand-in)."""
    proc = start_process(args)
    objective = make_objective(args)
    run_dir = open_run(args)
    views = open_store(args, store)
    net = build_network(args, proc)
    restore(net, args, run_dir, proc)
    write_config(run_dir, args, proc)
    distribute(net, proc)
    data = build_data(args, proc, views, run_dir, refreshable=store is None and not is_packed(args.data))
    train(args, proc, run_dir, net, data, objective)
    end_process(proc)
