"""The ``ssn-shadow`` command line."""

from __future__ import annotations

import argparse
import json
import sys
from collections.abc import Sequence
from pathlib import Path

EXIT_OK, EXIT_ERROR, EXIT_USAGE = 0, 1, 2


class CliError(Exception):
    """A user-facing error; ``code`` is the exit status."""

    def __init__(self, message: str, code: int = EXIT_USAGE) -> None:
        super().__init__(message)
        self.code = code


def _color(text: str) -> tuple[float, float, float]:
    value = text.lstrip("#")
    if len(value) != 6 or any(c not in "0123456789abcdefABCDEF" for c in value):
        raise argparse.ArgumentTypeError(f"expected a colour like #1a1a2e, got {text!r}")
    return tuple(int(value[i : i + 2], 16) / 255 for i in (0, 2, 4))  # type: ignore[return-value]


def _number_in(lo: float, hi: float):
    """An argparse type for a number in [lo, hi]."""

    def parse(text: str) -> float:
        try:
            value = float(text)
        except ValueError:
            raise argparse.ArgumentTypeError(f"expected a number, got {text!r}") from None
        if not lo <= value <= hi:
            raise argparse.ArgumentTypeError(f"expected a number in [{lo:g}, {hi:g}], got {text}")
        return value

    return parse


def _light_map(args: argparse.Namespace):
    from .light_map import LightMap, preset

    if args.light_map:
        try:
            return LightMap.from_json(Path(args.light_map).read_text())
        except OSError as exc:
            raise CliError(f"{args.light_map}: cannot read ({exc.strerror})") from None
    return preset(args.preset)


def _ao_edits(args: argparse.Namespace) -> list[dict]:
    edits: list[dict] = []
    if args.ao_edits:
        try:
            edits = json.loads(Path(args.ao_edits).read_text())
        except (OSError, json.JSONDecodeError) as exc:
            raise CliError(f"{args.ao_edits}: not a readable JSON list of AO edits ({exc})") from None
        if not isinstance(edits, list):
            raise CliError(f"{args.ao_edits}: expected a JSON list of AO edits")
    if args.ao_strength is not None:
        edits.append({"op": "strength", "value": args.ao_strength})
    return edits


def _make_shadow(cutout_rgba, args: argparse.Namespace):
    """Run the engine on a cutout; returns (CanvasShadow, method note)."""
    from .methods import load_method
    from .session import ShadowSession

    loaded = load_method(args.method)
    session = ShadowSession(cutout_rgba[..., 3], loaded.method, args.horizon, args.fov)
    session.set_ao_edits(_ao_edits(args))
    return session.render(_light_map(args)), loaded


def _write_outputs(cutout, shadow, args: argparse.Namespace, background=None) -> list[Path]:
    from .compositing import composite_shadow, over, shadow_layer
    from .imageio import load_rgba, save_png

    h, w = cutout.shape[:2]
    written = []
    if args.layer:
        full = shadow.full_canvas(w, h)
        written.append(save_png(args.layer, shadow_layer(full, args.color, args.opacity)))
    if args.composite:
        if background is None:
            background = load_rgba(args.background) if args.background else None
        if background is None:
            background = __import__("numpy").full((h, w, 4), 255, "uint8")
        if background.shape[:2] != (h, w):
            raise CliError(
                f"background is {background.shape[1]} x {background.shape[0]}, the cutout {w} x {h}: sizes must match"
            )
        shaded = composite_shadow(background, shadow.full_canvas(w, h), args.color, args.opacity)
        written.append(save_png(args.composite, over(shaded, cutout)))
    return written


def cmd_render(args: argparse.Namespace) -> int:
    from .imageio import load_rgba

    if not (args.layer or args.composite):
        raise CliError("nothing to write: give --layer and/or --composite")
    cutout = load_rgba(args.cutout)
    shadow, loaded = _make_shadow(cutout, args)
    for path in _write_outputs(cutout, shadow, args):
        print(f"wrote {path}")
    print(f"method: {loaded.method.name} ({loaded.note})")
    return EXIT_OK


DEMO_PRESET = "low-sun-left"  # the demo's light: a low sun, so the shadow it casts shows


def cmd_demo(args: argparse.Namespace) -> int:
    from .samples import pawn_cutout, save_samples, studio_background

    cutout, background = pawn_cutout(), studio_background()
    args.layer, args.composite, args.background = args.layer, args.out, None
    shadow, loaded = _make_shadow(cutout, args)
    for path in _write_outputs(cutout, shadow, args, background=background):
        print(f"wrote {path}")
    if args.save_samples:
        for path in save_samples(args.save_samples):
            print(f"wrote {path}")
    print(f"method: {loaded.method.name} ({loaded.note})")
    return EXIT_OK


def cmd_presets(args: argparse.Namespace) -> int:
    from .light_map import PRESETS, preset

    if args.name:
        print(preset(args.name).to_json())
        return EXIT_OK
    for name in PRESETS:
        lights = preset(name)
        print(f"{name:14s} {len(lights)} light{'s' if len(lights) > 1 else ''}")
    return EXIT_OK


def cmd_serve(args: argparse.Namespace) -> int:
    from .methods import load_method
    from .worker import serve_stdio, serve_tcp

    loaded = load_method(args.method)
    if args.port is None:
        serve_stdio(loaded)
    else:
        serve_tcp(loaded, args.port)
    return EXIT_OK


def cmd_benchmark(args: argparse.Namespace) -> int:
    from .benchmark import run_benchmark

    run_benchmark(repeats=args.repeats, method=args.method)
    return EXIT_OK


def cmd_install_plugin(args: argparse.Namespace) -> int:
    try:
        if args.host == "krita":
            from plugin_krita import install as host_install
        else:
            from plugin_gimp import install as host_install
    except ImportError as exc:
        raise CliError(f"the {args.host} plug-in is not part of this installation ({exc})", EXIT_ERROR) from None
    dest = Path(args.dest) if args.dest else None
    if args.zip:
        if args.host != "krita":
            raise CliError("--zip is for the Krita plug-in")
        print(f"wrote {host_install.build_zip(Path(args.zip))}")
        return EXIT_OK
    path = host_install.install(dest=dest, python=args.python, link=args.link)
    print(f"installed the {args.host} plug-in in {path}")
    return EXIT_OK


def _add_shadow_options(p: argparse.ArgumentParser) -> None:
    from .ao_edit import MAX_STRENGTH
    from .light_map import DEFAULT_PRESET, PRESETS
    from .methods import METHOD_NAMES

    light = p.add_mutually_exclusive_group()
    light.add_argument(
        "--preset", default=DEFAULT_PRESET, choices=list(PRESETS), help="light preset (default: %(default)s)"
    )
    light.add_argument("--light-map", metavar="ELM.json", help="light map JSON (see 'ssn-shadow presets NAME')")
    p.add_argument("--color", type=_color, default=(0.0, 0.0, 0.0), help="shadow colour, e.g. #1a1a2e (default black)")
    p.add_argument(
        "--opacity", type=_number_in(0.0, 1.0), default=0.85, help="shadow opacity in [0, 1] (default %(default)s)"
    )
    p.add_argument("--ao-edits", metavar="EDITS.json", help="JSON list of AO edits (docs/protocol.md)")
    p.add_argument(
        "--ao-strength", type=_number_in(0.0, MAX_STRENGTH), help="scale the contact (AO) occlusion; 0 removes it"
    )
    p.add_argument(
        "--method", default="auto", choices=METHOD_NAMES, help="auto: SSN if a model is installed, else geometric"
    )
    p.add_argument("--horizon", type=float, metavar="ROW",
                   help="the image's horizon: canvas row (pixels from the top; may be negative or past the bottom) "
                        "where the ground plane meets the sky; default: a camera pitched 15 degrees down")
    p.add_argument("--fov", type=_number_in(1.0, 170.0), metavar="DEG",
                   help="with --horizon: the image's vertical field of view in degrees (default 45)")


def build_parser() -> argparse.ArgumentParser:
    from . import __version__

    parser = argparse.ArgumentParser(prog="ssn-shadow", description="Soft shadows for 2D cutouts (SSN, CVPR 2021).")
    parser.add_argument("--version", action="version", version=f"ssn-shadow {__version__}")
    sub = parser.add_subparsers(dest="command", required=True, metavar="COMMAND")

    p = sub.add_parser("render", help="make a shadow layer and/or a composite for a cutout PNG")
    p.add_argument("cutout", help="RGBA image; its alpha is the cutout")
    p.add_argument("--layer", metavar="OUT.png", help="write the shadow layer (RGBA, canvas size)")
    p.add_argument("--composite", metavar="OUT.png", help="write cutout + shadow over --background")
    p.add_argument("--background", metavar="BG.png", help="background for --composite (default white)")
    _add_shadow_options(p)
    p.set_defaults(func=cmd_render)

    p = sub.add_parser("demo", help="render the bundled sample cutout over the bundled background")
    p.add_argument("--out", default="ssn-shadow-demo.png", help="composite PNG (default %(default)s)")
    p.add_argument("--layer", metavar="OUT.png", help="also write the shadow layer")
    p.add_argument("--save-samples", metavar="DIR", help="also write the sample cutout and background PNGs")
    _add_shadow_options(p)
    p.set_defaults(func=cmd_demo, preset=DEMO_PRESET)

    p = sub.add_parser("presets", help="list light presets, or print one as light-map JSON")
    p.add_argument("name", nargs="?", help="preset to print as JSON")
    p.set_defaults(func=cmd_presets)

    from .methods import METHOD_NAMES

    p = sub.add_parser("serve", help="run the engine worker for the plug-ins (docs/protocol.md)")
    p.add_argument("--port", type=int, help="listen on 127.0.0.1:PORT (0 = any free port) instead of stdin/stdout")
    p.add_argument("--method", default="auto", choices=METHOD_NAMES)
    p.set_defaults(func=cmd_serve)

    p = sub.add_parser("benchmark", help="time AOP, SR, the geometric method and end to end")
    p.add_argument("--repeats", type=int, default=20, help="timed runs per figure (default %(default)s)")
    p.add_argument("--method", default="auto", choices=METHOD_NAMES)
    p.set_defaults(func=cmd_benchmark)

    p = sub.add_parser("install-plugin", help="install the Krita or GIMP plug-in for this engine")
    p.add_argument("host", choices=["krita", "gimp"])
    p.add_argument("--dest", help="plug-in folder (default: the host's user folder for this OS)")
    p.add_argument("--python", help="Python that runs the engine (default: this one)")
    p.add_argument("--link", action="store_true", help="symlink instead of copying (for development)")
    p.add_argument("--zip", metavar="OUT.zip", help="Krita: build a zip for 'Import Python Plugin from File'")
    p.set_defaults(func=cmd_install_plugin)
    return parser


def main(argv: Sequence[str] | None = None) -> int:
    """Run the CLI; returns the exit status."""
    args = build_parser().parse_args(argv)
    from .framing import EmptyAlphaError
    from .imageio import ImageFileError
    from .light_map import LightMapError
    from .methods import ModelError

    try:
        return args.func(args)
    except CliError as exc:
        print(f"ssn-shadow: error: {exc}", file=sys.stderr)
        return exc.code
    except (ImageFileError, LightMapError, EmptyAlphaError, ValueError) as exc:
        print(f"ssn-shadow: error: {exc}", file=sys.stderr)
        return EXIT_USAGE
    except ModelError as exc:
        print(f"ssn-shadow: error: {exc}", file=sys.stderr)
        return EXIT_ERROR
    except KeyboardInterrupt:
        return 130


if __name__ == "__main__":
    raise SystemExit(main())
