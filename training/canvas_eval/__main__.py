"""Canvas-scale evaluation of shadows under disk lights (docs/canvas_eval.md).

python -m training.canvas_eval render [--out data/canvas_test] [--width 1024 --height 768] [--shapes 12]
python -m training.canvas_eval score --method cli [--data data/canvas_test] [--repo DIR] [--python EXE]
                                     --out data/canvas_eval/NAME
python -m training.canvas_eval sheet --predictions data/canvas_eval/NAME [--out docs/img/canvas_eval_sheet.png]
python -m training.canvas_eval prepare-outsource --git MIRROR [--out data/outsource_meshes]
python -m training.canvas_eval mitsuba [--data data/canvas_test] [--groups 3]
python -m training.canvas_eval oracle [--data data/canvas_test] [--out data/canvas_eval/oracle.json] [--sheet PNG]
"""

from __future__ import annotations

import argparse
import sys
from pathlib import Path

from training.data import render_bases

from .mitsuba_check import compare
from .oracle import run_oracle
from .out_of_source import prepare
from .render_set import render_set
from .score import run_scoring
from .sheet import write_sheet

DEFAULT_DATA = Path("data/canvas_test")


def _render(args: argparse.Namespace) -> int:
    render_bases.set_threads(args.threads)
    render_set(
        args.out, args.width, args.height, args.shapes, args.lights, args.seed, split=args.split, floating=args.floating
    )
    return 0


def _prepare(args: argparse.Namespace) -> int:
    prepare(args.git, args.out)
    return 0


def _score(args: argparse.Namespace) -> int:
    run_scoring(args.data, args.out, args.repo, args.python, args.modes, args.engine_args, args.jobs, args.max_groups)
    return 0


def _sheet(args: argparse.Namespace) -> int:
    write_sheet(args.data, args.predictions, args.out, args.groups, args.mode, args.angles)
    return 0


def _mitsuba(args: argparse.Namespace) -> int:
    compare(args.data, args.groups, args.samples, args.stride)
    return 0


def _oracle(args: argparse.Namespace) -> int:
    run_oracle(args.data, args.out, args.groups, args.sheet)
    return 0


def build_parser() -> argparse.ArgumentParser:
    p = argparse.ArgumentParser(
        prog="python -m training.canvas_eval", description="Canvas-scale evaluation of shadows under disk lights."
    )
    sub = p.add_subparsers(dest="command", required=True)

    r = sub.add_parser("render", help="render the test set's truths (resumes)")
    r.add_argument("--out", type=Path, default=DEFAULT_DATA)
    r.add_argument("--width", type=int, default=1024)
    r.add_argument("--height", type=int, default=768)
    r.add_argument("--shapes", type=int, help="only the first SHAPES picked shapes (default: all 12)")
    r.add_argument("--lights", type=int, default=2, help="light directions per shape (default %(default)s)")
    r.add_argument("--seed", type=int, default=0)
    r.add_argument("--threads", type=int, default=1)
    r.add_argument(
        "--split",
        choices=["test", "val", "outsource"],
        default="test",
        help="whose shapes: the test set's, the validation shapes' (a set to choose models by), or every shape "
        "of the out-of-source folder (prepare-outsource; SSN_MESHES pointing at it)",
    )
    r.add_argument(
        "--floating",
        action="store_true",
        help="each shape floats 0.15 to 0.8 of its height above the ground; 0.53 and 3 degree lights; scored with "
        "its true lift (--lift) and camera",
    )
    r.set_defaults(func=_render)

    q = sub.add_parser("prepare-outsource", help="write the out-of-source test shapes from a snapshot of their source")
    q.add_argument(
        "--git", type=Path, required=True, help="a git snapshot (bare) of alecjacobson/common-3d-test-models"
    )
    q.add_argument("--out", type=Path, default=Path("data/outsource_meshes"))
    q.set_defaults(func=_prepare)

    s = sub.add_parser("score", help="render every case through the CLI and score it against the truth")
    s.add_argument("--method", choices=["cli"], default="cli", help="how predictions are made (the CLI)")
    s.add_argument("--data", type=Path, default=DEFAULT_DATA, help="the rendered test set")
    s.add_argument("--out", type=Path, required=True, help="folder for the predictions, scores.json and table.md")
    s.add_argument("--repo", type=Path, default=Path.cwd(), help="repository whose engine to run (default: here)")
    s.add_argument("--python", default=sys.executable, help="Python that runs the engine (default: this one)")
    s.add_argument("--modes", nargs="+", choices=["camera", "blind"], default=["camera", "blind"])
    s.add_argument("--engine-args", default="", help="extra 'ssn-shadow render' options, e.g. '--method geometric'")
    s.add_argument("--jobs", type=int, default=1, help="CLI runs at once (default %(default)s)")
    s.add_argument("--max-groups", type=int, help="score only this many groups, spread over the set (quicker)")
    s.set_defaults(func=_score)

    t = sub.add_parser("sheet", help="picture sheet: truth vs prediction under the three sizes")
    t.add_argument("--data", type=Path, default=DEFAULT_DATA)
    t.add_argument("--predictions", type=Path, nargs="+", required=True, help="'score --out' folders, side by side")
    t.add_argument("--out", type=Path, default=Path("docs/img/canvas_eval_sheet.png"))
    t.add_argument("--groups", nargs="+", help="groups to show (default: four spread over the set)")
    t.add_argument("--mode", choices=["camera", "blind"], default="camera")
    t.add_argument("--angles", type=float, nargs="+", help="only these light sizes (degrees)")
    t.set_defaults(func=_sheet)

    m = sub.add_parser("mitsuba", help="check truths against Mitsuba 3 ray casting (needs mitsuba)")
    m.add_argument("--data", type=Path, default=DEFAULT_DATA)
    m.add_argument("--groups", type=int, default=3, help="groups to check (spread over the set)")
    m.add_argument("--samples", type=int, default=1024, help="random directions per pixel in the disk")
    m.add_argument("--stride", type=int, default=4, help="check every STRIDE-th pixel in each direction")
    m.set_defaults(func=_mitsuba)

    o = sub.add_parser("oracle", help="score the traced representation given the true geometry (0.53 degrees)")
    o.add_argument("--data", type=Path, default=DEFAULT_DATA)
    o.add_argument("--out", type=Path, help="write the scores here (json)")
    o.add_argument("--groups", nargs="+", help="only these groups (default: all)")
    o.add_argument("--sheet", type=Path, help="write a picture of the truth and the variants for four groups here")
    o.set_defaults(func=_oracle)
    return p


def main(argv: list[str] | None = None) -> int:
    args = build_parser().parse_args(argv)
    return args.func(args)


if __name__ == "__main__":
    sys.exit(main())
