"""Write a model folder from training checkpoints: the ONNX graphs, model.json and the model card.

:func:`export_model` does what ``python -m training.export`` asks (:mod:`training.export` lists the options):
each graph exported (float32 weights) and checked against its torch network (:mod:`training.onnx_graphs`), the
SR's latency timed, :class:`ssn_engine.model_config.ModelConfig` filled in and
written, the card beside it (:mod:`training.model_card`), and optionally installed.
"""

from __future__ import annotations

import dataclasses
import shutil
from pathlib import Path

import numpy as np

from ssn_engine.frames import resample_frames
from ssn_engine.hemisphere import network_elm
from ssn_engine.benchmark import time_calls
from ssn_engine.model_config import ModelConfig

from .checkpoint import load_models
from .data.store import ViewStore
from .elm import TRAIN_MIX, render_lights, sample_lights
from .model import MirrorAverage
from .model_card import MIX_RECORD, mesh_attribution, model_card, training_summary
from .onnx_graphs import (
    TOL,
    export_graph,
    parity,
    session,
    takes_camera,
    without_mirror_average,
)

__all__ = ["ExportError", "ExportOptions", "export_model", "reuse_aop", "reuses_aop_graph", "sample_inputs", "time_sr"]

MODEL_FILES = ("aop.onnx", "sr.onnx", "aop_camera.onnx", "model.json", "MODEL_CARD.md")


class ExportError(RuntimeError):
    """The checkpoints do not make the model asked for, or a graph failed its parity check."""


@dataclasses.dataclass(frozen=True)
class ExportOptions:
    """What ``python -m training.export`` asks for (its options, same names)."""

    aop: list[str]
    sr: str
    out: Path
    aop_camera: list[str] | None = None
    data: str = "data/ssn128"
    tol: float = TOL
    floor: float = 0.0
    floor_small_lights: float | None = None
    shadow_reach: float = 0.0
    ao_gamma: float = 1.0
    card_blur: float | None = None
    mirror_average: bool = False
    aop_without_mirror: bool = False
    install: Path | None = None
    command: str = "training/reproduce.sh"
    trained_on: str = ""


def sample_inputs(data: str | None, resolution: int, n: int = 8, seed: int = 0) -> dict[str, np.ndarray]:
    """Masks and AO maps of test views (random blobs without data) and random Table 1 ELMs."""
    rng = np.random.default_rng(seed)
    if data and Path(data, "dataset.json").is_file():
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


def time_sr(path: Path, resolution: int, repeats: int = 30) -> dict[str, float]:
    """Median SR latency (one image) through onnxruntime: at R alone, and the engine's N = 256 path."""
    s = session(path)
    card = "card" in {i.name for i in s.get_inputs()}
    mask = np.random.default_rng(0).random((1, 1, resolution, resolution), dtype=np.float32)
    feeds = {"mask": mask, "ao": mask, "elm": np.random.default_rng(1).random((1, 16, 32), dtype=np.float32)}
    feeds.update({"card": mask} if card else {})
    frame = np.random.default_rng(2).random((1, 256, 256), dtype=np.float32)

    def engine_path():
        m = resample_frames(frame, resolution)[:, None]
        run_feeds = {"mask": m, "ao": m, "elm": feeds["elm"], **({"card": m} if card else {})}
        out = np.asarray(s.run(None, run_feeds)[0])[:, 0]
        return resample_frames(out, 256)

    out = {}
    for name, fn in (("sr_at_R_ms", lambda: s.run(None, feeds)), ("sr_engine_256_ms", engine_path)):
        out[name] = float(np.median(time_calls(fn, repeats, warmup=1)))
    return out


def reuse_aop(graph: Path, out: Path, drop_mirror: bool = False) -> dict:
    """Copy an installed aop.onnx into ``out`` (``drop_mirror``: :func:`without_mirror_average` of it); its record
    from the model.json beside it (or a bare one)."""
    if drop_mirror:
        without_mirror_average(graph, out / "aop.onnx")
    elif graph.resolve() != (out / "aop.onnx").resolve():
        shutil.copy(graph, out / "aop.onnx")
    meta = graph.with_name("model.json")
    record = (ModelConfig.from_json(meta.read_text()).export or {}).get("aop", {}) if meta.is_file() else {}
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


def _export_one(name: str, module: str, ck_paths: list[str], x: dict, opt: ExportOptions, report: dict) -> int:
    """Export graph ``name`` (``module`` aop or sr) of the checkpoints ``ck_paths`` into ``opt.out``; its record
    goes into ``report``. Returns the checkpoints' resolution R."""
    net, cks = load_models(ck_paths)
    if module == "aop" and takes_camera(net) != (name == "aop_camera"):
        raise ExportError(
            f"--{name.replace('_', '-')}: {' '.join(ck_paths)} must be AOPs "
            f"{'with' if name == 'aop_camera' else 'without'} the camera input (train --camera)"
        )
    # A camera-taking AOP is not mirror-averaged: its camera input is no image to mirror (the shipped AOP runs once
    # anyway, docs/training.md).
    mirrored = opt.mirror_average and name != "aop_camera"
    net = MirrorAverage(net).eval() if mirrored else net
    r = cks[0]["unet"]["resolution"]
    out = opt.out
    export_graph(net, module, r, out / f"{name}.onnx")
    diff = parity(out / f"{name}.onnx", net, module, x)
    report[f"{name}_parity_fp32"] = diff
    report[name] = {
        "checkpoints": [str(p) for p in ck_paths],
        "steps": [ck["step"] for ck in cks],
        "samples": [ck["samples"] for ck in cks],
        "widths": [ck["unet"]["widths"] for ck in cks],
        "rebuilt_from": [ck.get("rebuilt_from") for ck in cks],  # training.onnx_weights: a graph's network
        "weights": "float32",
        "mirror_average": mirrored,
        "max_abs_diff": diff,
        "bytes": (out / f"{name}.onnx").stat().st_size,
    }
    if diff > opt.tol:
        raise ExportError(f"{name}: parity FAILED: max abs diff {diff:.2e} > {opt.tol:.0e}")
    print(
        f"{name}: float32 weights, max abs diff to torch {diff:.2e}, {report[name]['bytes'] / 1e6:.2f} MB",
        flush=True,
    )
    return r


def reuses_aop_graph(aop: list[str], without_mirror: bool) -> bool:
    """Whether ``--aop`` names an installed graph to reuse rather than checkpoints; ExportError where
    ``without_mirror`` (--aop-without-mirror) asks to rewrite a graph that is not given."""
    reused = len(aop) == 1 and aop[0].endswith(".onnx")
    if without_mirror and not reused:
        raise ExportError("--aop-without-mirror rewrites an installed aop.onnx: give one as --aop")
    return reused


def export_model(opt: ExportOptions) -> ModelConfig:
    """Write the model ``opt`` describes into ``opt.out`` (and ``opt.install``); returns its configuration.

    Raises
    ------
    ExportError
        A checkpoint is of the wrong kind, or a graph is further than ``opt.tol`` from its network.
    """
    reused = reuses_aop_graph(opt.aop, opt.aop_without_mirror)
    out = opt.out
    out.mkdir(parents=True, exist_ok=True)
    report: dict = {}
    resolution = None
    x: dict | None = None
    graphs = [("aop", "aop", opt.aop), ("sr", "sr", [opt.sr])]
    if opt.aop_camera:
        graphs.append(("aop_camera", "aop", opt.aop_camera))
    for name, module, ck_paths in graphs:
        if name == "aop" and reused:
            report["aop"] = reuse_aop(Path(ck_paths[0]), out, opt.aop_without_mirror)
            without = " without its mirror average" if opt.aop_without_mirror else ""
            print(f"aop: reused {ck_paths[0]}{without}", flush=True)
            continue
        if x is None:
            r = load_models(ck_paths)[1][0]["unet"]["resolution"]
            x = sample_inputs(opt.data, r)
        resolution = _export_one(name, module, ck_paths, x, opt, report)
    assert resolution is not None  # the SR is always exported
    sr_ck = load_models([opt.sr])[1][0]
    on = f", on {opt.trained_on}" if opt.trained_on else ""
    blur = sr_ck["args"].get("card_blur", 0.0) if opt.card_blur is None else opt.card_blur
    lights = sr_ck["args"].get("lights", "table1")
    report["timing"] = time_sr(out / "sr.onnx", resolution)
    print(
        f"SR median latency (onnxruntime, this CPU): {report['timing']['sr_at_R_ms']:.1f} ms at R = "
        f"{resolution}, {report['timing']['sr_engine_256_ms']:.1f} ms on a 256 frame incl. resampling"
    )
    config = ModelConfig(
        aop_camera="aop_camera.onnx" if opt.aop_camera else None,
        output_floor=opt.floor,
        mirror_average=opt.mirror_average,
        output_floor_small_lights=opt.floor_small_lights,
        shadow_reach=opt.shadow_reach,
        ao_gamma=opt.ao_gamma,
        resolution=resolution,
        card_input=bool(sr_ck["unet"].get("card")),
        sr_training=training_summary(Path(opt.sr), sr_ck) + on,
        card_blur=blur,
        lights=f"{MIX_RECORD} {TRAIN_MIX}" if lights == "mix" else "the paper's Table 1",
        export=report,
        training_data=opt.data,
    )
    (out / "model.json").write_text(config.to_json())
    (out / "MODEL_CARD.md").write_text(model_card(config, mesh_attribution(opt.data), opt.command))
    if opt.install:
        opt.install.mkdir(parents=True, exist_ok=True)
        for name in MODEL_FILES:
            if (out / name).is_file():
                shutil.copy(out / name, opt.install / name)
            else:
                (opt.install / name).unlink(missing_ok=True)  # a model without an optional graph replaces one with it
        print(f"installed into {opt.install}")
    return config
