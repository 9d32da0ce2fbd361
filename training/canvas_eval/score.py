"""Score an engine on the canvas test set through its command line (conventions, "Canvas-level entry point").

Each case runs ``PYTHON -m ssn_engine render CUTOUT.png --light-map LIGHT.json [--horizon ROW --fov DEG]
--opacity 1 --layer OUT.png`` in the repository ``REPO`` (on ``PYTHONPATH``), with the true camera
("camera") and without it ("blind"); the layer's alpha / 255 is the predicted s. Predictions are kept under
``OUT/pred/``, so a second run only makes the missing ones.
"""

from __future__ import annotations

import json
import os
import shlex
import subprocess
import time
from concurrent.futures import ThreadPoolExecutor
from pathlib import Path

import numpy as np
from PIL import Image

from . import cases, metrics

MODES = ("camera", "blind")
MEAN_METRICS = ("zncc", "dssim", "bandpass_zncc", "iou")  # averaged; the ratios get their median (they are skewed)
LABELS = {
    "zncc": "ZNCC",
    "dssim": "DSSIM",
    "bandpass_zncc": "band-pass ZNCC",
    "gradient_energy": "gradient energy",
    "dark_ratio": "p99.9 dark ratio",
    "iou": "IoU (s >= 0.5)",
    "outline_distance": "outline distance (px, median)",
    "gap_ratio": "gap ratio",
    "contact_ratio": "contact ratio",
}


def prediction_path(out: Path, mode: str, group: cases.Group, angle: float) -> Path:
    return Path(out) / "pred" / mode / group.name / f"layer_{cases.angle_tag(angle)}.png"


def cli_command(
    python: str, data: Path, group: cases.Group, angle: float, mode: str, layer: Path, engine_args: str = ""
) -> list[str]:
    """The conventions' canvas-level command for one case (``mode`` "camera" adds the true camera)."""
    cmd = [
        python,
        "-m",
        "ssn_engine",
        "render",
        str(cases.cutout_path(data, group).resolve()),
        "--light-map",
        str(cases.light_path(data, group, angle).resolve()),
        "--opacity",
        "1",
        "--layer",
        str(layer.resolve()),
    ]
    if mode == "camera":
        cmd += ["--horizon", f"{group.horizon:.4f}", "--fov", f"{group.fov:.4f}"]
        if group.lift > 0:  # a floating case: its true lift with its true camera
            cmd += ["--lift", f"{group.lift:.2f}"]
    elif mode != "blind":
        raise ValueError(f"mode must be one of {MODES}, got {mode!r}")
    return cmd + shlex.split(engine_args)


def run_cli(cmd: list[str], repo: Path, layer: Path) -> float:
    """Run one case's command in ``repo`` (on PYTHONPATH); returns its wall seconds.

    Raises
    ------
    RuntimeError
        The command failed or wrote no layer; the message holds its last output.
    """
    layer.parent.mkdir(parents=True, exist_ok=True)
    env = dict(os.environ)
    env["PYTHONPATH"] = os.pathsep.join([str(Path(repo).resolve()), *filter(None, [env.get("PYTHONPATH")])])
    t0 = time.perf_counter()
    done = subprocess.run(cmd, cwd=repo, env=env, capture_output=True, text=True)
    seconds = time.perf_counter() - t0
    if done.returncode != 0 or not layer.is_file():
        tail = (done.stdout + done.stderr).strip().splitlines()[-5:]
        raise RuntimeError(f"{shlex.join(cmd)} failed (exit {done.returncode}):\n" + "\n".join(tail))
    return seconds


def read_layer(path: Path, shape: tuple[int, int]) -> np.ndarray:
    """A shadow layer's alpha / 255, (H, W) float32; the layer must be canvas-sized."""
    with Image.open(path) as im:
        alpha = np.asarray(im.convert("RGBA"))[..., 3]
    if alpha.shape != shape:
        raise ValueError(
            f"{path}: the layer is {alpha.shape[1]} x {alpha.shape[0]}, the canvas {shape[1]} x {shape[0]}"
        )
    return alpha.astype(np.float32) / 255.0


def summarise(rows: list[dict], by: str) -> dict[str, dict[str, float]]:
    """Per value of ``by`` (and "all"): n, the mean of ``MEAN_METRICS``, the median of the ratios (nan
    ignored) and how many cases have a contact ratio."""
    keys = ["all", *sorted({str(r[by]) for r in rows}, key=_order)]
    out = {}
    for key in keys:
        sel = rows if key == "all" else [r for r in rows if str(r[by]) == key]
        entry: dict[str, float] = {"n": len(sel)}
        for name in metrics.NAMES:
            vals = np.array([r[name] for r in sel], np.float64)
            vals = vals[np.isfinite(vals)]
            entry[name] = (
                float("nan") if not vals.size else float(vals.mean() if name in MEAN_METRICS else np.median(vals))
            )
        entry["contact_n"] = int(sum(np.isfinite(r["contact_ratio"]) for r in sel))
        out[key] = entry
    return out


def _order(key: str) -> tuple[int, float | str]:
    try:
        return 0, float(key)
    except ValueError:
        return 1, key


def markdown_table(summary: dict[str, dict[str, dict[str, dict[str, float]]]]) -> str:
    """One table per mode: rows all / by light size / by kind / by pitch, a column per metric."""
    head = "| cases | n | " + " | ".join(LABELS[n] for n in metrics.NAMES) + " |"
    lines = []
    for mode, by_field in summary.items():
        lines += [
            f"**{'with the true camera' if mode == 'camera' else 'blind (camera inferred)'}**",
            "",
            head,
            "|---|---:|" + "---:|" * len(metrics.NAMES),
        ]
        for field, label in (("angle", "{} deg"), ("kind", "{}"), ("pitch", "pitch {}")):
            for key, entry in by_field[field].items():
                if key == "all" and field != "angle":
                    continue
                name = "all" if key == "all" else label.format(key)
                cells = [f"{entry[n]:.3f}" for n in metrics.NAMES[:-1]]
                cells.append(f"{entry['contact_ratio']:.3f} ({entry['contact_n']})")
                lines.append(f"| {name} | {entry['n']} | " + " | ".join(cells) + " |")
        lines.append("")
    return "\n".join(lines)


def _revision(repo: Path) -> str:
    done = subprocess.run(["git", "-C", str(repo), "describe", "--always", "--dirty"], capture_output=True, text=True)
    return done.stdout.strip() or "unknown"


def spread(groups: list[cases.Group], count: int | None) -> list[cases.Group]:
    """``count`` of ``groups`` (all of them when None or not fewer), picked one at a time to even out the
    pitches first, then to use distinct shapes, then to keep the kinds in the set's proportions."""
    if count is None or count >= len(groups):
        return groups
    if count < 1:
        raise ValueError(f"max_groups must be at least 1, got {count}")
    kinds = {g.kind: sum(h.kind == g.kind for h in groups) for g in groups}
    chosen: list[cases.Group] = []

    def cost(k: int) -> tuple[int, int, float, int]:
        g = groups[k]
        return (
            sum(c.pitch == g.pitch for c in chosen),
            sum(c.shape == g.shape for c in chosen),
            sum(c.kind == g.kind for c in chosen) / kinds[g.kind],
            k,
        )

    left = list(range(len(groups)))
    for _ in range(count):
        best = min(left, key=cost)
        left.remove(best)
        chosen.append(groups[best])
    return [g for g in groups if g in chosen]


def run_scoring(
    data: Path,
    out: Path,
    repo: Path,
    python: str,
    modes: list[str] | tuple[str, ...] = MODES,
    engine_args: str = "",
    jobs: int = 1,
    max_groups: int | None = None,
    log=print,
) -> dict:
    """Make the missing predictions, score every case, write ``OUT/scores.json`` and ``OUT/table.md``.

    ``max_groups`` scores only that many groups, spread evenly over the set (quicker, every kind and pitch
    still present when it is at least 6); None scores them all.

    Returns
    -------
    dict
        ``settings``, ``cases`` (one row per case and mode) and ``summary`` (per mode, by angle, kind, pitch).
    """
    data, out, repo = Path(data), Path(out), Path(repo)
    groups = spread(cases.read_groups(data), max_groups)
    missing = [p for g in groups for a in g.angles if not (p := cases.truth_path(data, g, a)).is_file()]
    if missing:
        raise FileNotFoundError(
            f"{len(missing)} truths are missing, e.g. {missing[0]}: finish the set with "
            "'python -m training.canvas_eval render' first"
        )
    todo = [(g, a, m) for m in modes for g in groups for a in g.angles]
    seconds: dict[tuple[str, float, str], float] = {}

    def make(task: tuple[cases.Group, float, str]) -> None:
        group, angle, mode = task
        layer = prediction_path(out, mode, group, angle)
        if not layer.is_file():
            part = layer.with_name(layer.stem + ".part.png")  # renamed when complete: an interrupted run resumes
            seconds[(group.name, angle, mode)] = run_cli(
                cli_command(python, data, group, angle, mode, part, engine_args), repo, part
            )
            os.replace(part, layer)

    with ThreadPoolExecutor(max(1, jobs)) as pool:
        for i, _ in enumerate(pool.map(make, todo)):
            if (i + 1) % 12 == 0 or i + 1 == len(todo):
                log(f"[{i + 1}/{len(todo)}] predictions")
    rows = []
    for i, group in enumerate(groups):
        log(f"[{i + 1}/{len(groups)}] scoring {group.name}")
        mask = cases.read_mask(data, group)
        for angle in group.angles:
            truth = cases.read_truth(data, group, angle)
            for mode in modes:
                pred = read_layer(prediction_path(out, mode, group, angle), truth.shape)
                row = {
                    "group": group.name,
                    "shape": group.shape,
                    "kind": group.kind,
                    "pitch": group.pitch,
                    "angle": angle,
                    "mode": mode,
                    "seconds": seconds.get((group.name, angle, mode)),
                }
                row.update(metrics.score_case(pred, truth, mask, group.horizon))
                rows.append(row)
    summary = {
        mode: {by: summarise([r for r in rows if r["mode"] == mode], by) for by in ("angle", "kind", "pitch")}
        for mode in modes
    }
    result = {
        "settings": {
            "data": str(data),
            "repo": str(repo.resolve()),
            "revision": _revision(repo),
            "python": python,
            "engine_args": engine_args,
            "groups": len(groups),
        },
        "cases": rows,
        "summary": summary,
    }
    out.mkdir(parents=True, exist_ok=True)
    (out / "scores.json").write_text(json.dumps(result, indent=1))
    table = markdown_table(summary)
    (out / "table.md").write_text(table + "\n")
    log(table)
    return result


__all__ = [
    "MODES",
    "cli_command",
    "markdown_table",
    "prediction_path",
    "read_layer",
    "run_cli",
    "run_scoring",
    "spread",
    "summarise",
]
