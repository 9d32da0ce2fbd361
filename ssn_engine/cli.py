"""The ``ssn-shadow`` command line.

Only the standard library is imported before :func:`main` starts: a Ctrl+C while numpy or the model loads is
then answered like any other (exit status 130, what was written, no traceback).
"""

from __future__ import annotations

import argparse
import contextlib
import math
import os
import signal
import sys
import threading
import time
from collections.abc import Iterator, Sequence
from pathlib import Path
from typing import TYPE_CHECKING, Any

from .host_kit import defaults
from .host_kit.ao_edits import strength_edits
from .host_kit.camera_rules import DEFAULT_FOV, FOV_RANGE
from .host_kit.geometry_rules import THICKNESS_RANGE

if TYPE_CHECKING:
    import numpy as np

EXIT_OK, EXIT_ERROR, EXIT_USAGE = 0, 1, 2
EXIT_NO_SHADOW = 3  # nothing casts a shadow or nothing lights it: nothing is written
EXIT_INTERRUPTED = 130  # Ctrl+C, as a shell reports a command ended by SIGINT
PROGRESS_AFTER = 1.0  # seconds: a command that runs longer prints its stages on stderr
PLUGIN_ENTRY_POINTS = "ssn_shadow.plugins"  # the plug-ins' installers (pyproject.toml), not imported by the engine


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
            limits = f"a number >= {lo:g}" if hi == math.inf else f"a number in [{lo:g}, {hi:g}]"
            raise argparse.ArgumentTypeError(f"expected {limits}, got {text}")
        return value

    return parse


class Interrupted(KeyboardInterrupt):
    """Ctrl+C, as :class:`CtrlC` raises it. A plain KeyboardInterrupt that has passed through some C code (an
    import, for one) makes Python end the process by SIGINT at exit, even once it is caught; a subclass does
    not, so the exit status stays 130."""


class CtrlC:
    """The CLI's SIGINT handler: it raises :class:`Interrupted`, except inside :meth:`held`, where it only
    records the interrupt and the block raises it as it ends."""

    def __init__(self) -> None:
        self._holding = self._pending = False

    def __call__(self, signum: int, frame: object) -> None:
        if self._holding:
            self._pending = True
        else:
            raise Interrupted

    @contextlib.contextmanager
    def held(self) -> Iterator[None]:
        """Hold Ctrl+C over a block that must not be cut short: loading numpy or onnxruntime, whose
        initialisation turns an exception raised inside it into an ImportError."""
        self._holding, self._pending = True, False
        try:
            yield
        finally:
            self._holding = False
        if self._pending:
            raise Interrupted


CTRL_C = CtrlC()


class NoShadow(Exception):
    """There is no visible shadow to write (an empty cutout, or a light map without light)."""


class Stages:
    """Progress on stderr for a command that runs longer than ``after`` seconds: the stage it is in then, and
    each later one."""

    def __init__(self, after: float | None = None, stream=None) -> None:
        after = PROGRESS_AFTER if after is None else after
        self.start, self.stream, self.current, self.shown = time.monotonic(), stream or sys.stderr, "", False
        self._lock = threading.Lock()
        self._timer = threading.Timer(after, self._late)
        self._timer.daemon = True
        self._timer.start()

    def _print(self) -> None:
        print(f"ssn-shadow: [{time.monotonic() - self.start:5.1f} s] {self.current}...", file=self.stream, flush=True)

    def _late(self) -> None:
        with self._lock:
            self.shown = True
            if self.current:
                self._print()

    def __call__(self, label: str) -> None:
        with self._lock:
            self.current = label
            if self.shown:
                self._print()

    def close(self) -> None:
        self._timer.cancel()


def _same_file(a: Path, b: Path) -> bool:
    """Whether two paths name one file: the same resolved path, or (both existing) the same inode."""
    if a.resolve() == b.resolve():
        return True
    try:
        return a.exists() and b.exists() and os.path.samefile(a, b)
    except OSError:
        return False


def _read_only(path: Path) -> bool:
    """Whether an existing file forbids writing: to this user, or to everyone (a 0444 file, which root could
    otherwise replace)."""
    return not os.access(path, os.W_OK) or not path.stat().st_mode & 0o222


def check_paths(outputs: dict[str, str | None], inputs: dict[str, str | None]) -> None:
    """Before any work: every output names a file (no trailing slash), goes to an existing, writable folder
    (through a symbolic link: its target's), is not a folder, a special file or a read-only file, differs from
    the other outputs and from every input (by path or by inode)."""
    outs = [(label, Path(p)) for label, p in outputs.items() if p]
    ins = [(label, Path(p)) for label, p in inputs.items() if p]
    for label, p in outputs.items():
        if p and p.endswith(("/", os.sep)):
            raise CliError(f"{label} {p}: ends with a slash, so it names a folder; give a file name")
    for i, (label, path) in enumerate(outs):
        target = Path(os.path.realpath(path)) if path.is_symlink() else path  # a link is written through
        folder = target.parent
        if not folder.is_dir():
            raise CliError(f"{label} {path}: folder {folder} does not exist")
        if target.is_dir():
            raise CliError(f"{label} {path}: is a folder; give a file name")
        if target.exists() and not target.is_file():
            raise CliError(f"{label} {path}: is not a regular file (a device, pipe or socket); give a file name")
        if target.exists() and _read_only(target):
            raise CliError(
                f"{label} {path}: is read-only; ssn-shadow does not replace a read-only file (make it writable or "
                "choose another path)"
            )
        if not os.access(folder, os.W_OK):
            raise CliError(f"{label} {path}: folder {folder} is not writable")
        for other_label, other in outs[:i]:
            if _same_file(path, other):
                raise CliError(f"{other_label} and {label} name the same file ({path}); give two different paths")
        for in_label, source in ins:
            if _same_file(path, source):
                raise CliError(
                    f"{label} {path} is {in_label}: ssn-shadow never writes over its inputs; choose another output path"
                )


def check_folder(label: str, folder: str | None) -> None:
    if folder and not Path(folder).is_dir():
        raise CliError(f"{label} {folder}: no such folder")


def _light_map(args: argparse.Namespace):
    from .host_kit.light_map import LightMap, LightMapError, preset
    from .host_kit.shadow_notes import NO_LIGHT

    if args.light_map:
        try:
            lights = LightMap.from_json(Path(args.light_map).read_text(encoding="utf-8"))
        except OSError as exc:
            raise CliError(f"{args.light_map}: cannot read ({exc.strerror})") from None
        except UnicodeDecodeError:
            raise CliError(f"{args.light_map}: not a light map (not UTF-8 JSON text)") from None
        except LightMapError as exc:
            raise CliError(f"{args.light_map}: {exc}") from None
    else:
        lights = preset(args.preset)
    if lights.is_dark:
        raise NoShadow(f"{args.light_map or args.preset}: {NO_LIGHT}")
    return lights


def _ao_edits(args: argparse.Namespace) -> list[dict]:
    from .host_kit.protocol import loads

    edits: list[dict] = []
    if args.ao_edits:
        try:
            edits = loads(Path(args.ao_edits).read_text(encoding="utf-8"))
        except (OSError, ValueError) as exc:  # JSONDecodeError, NestingError and UnicodeDecodeError are ValueErrors
            raise CliError(f"{args.ao_edits}: not a readable JSON list of AO edits ({exc})") from None
        if not isinstance(edits, list):
            raise CliError(f"{args.ao_edits}: expected a JSON list of AO edits")
    if args.ao_strength is not None:
        edits.extend(strength_edits(args.ao_strength))
    return edits


def load_cutout(args: argparse.Namespace) -> np.ndarray:
    """The cutout as RGBA uint8. Without alpha, or opaque on its whole frame, it is not a cutout: refused
    unless ``--whole-image``."""
    from .imageio import load_image

    rgba, has_alpha = load_image(args.cutout, args.max_megapixels)
    if args.whole_image:
        return rgba
    how = (
        "Make a cutout first: erase the background around the subject to transparency (Krita, GIMP: add an "
        "alpha channel, select the background, delete) and save it as PNG; or pass --whole-image to cast the "
        "shadow of the whole rectangle."
    )
    if not has_alpha:
        raise CliError(f"{args.cutout} has no alpha channel, so it holds no cutout. {how}")
    if rgba[..., 3].min() >= 128:
        raise CliError(f"{args.cutout} is opaque on its whole frame, so its cutout is the whole rectangle. {how}")
    return rgba


def _make_shadow(cutout_rgba: np.ndarray, args: argparse.Namespace, stage: Stages):
    """The canvas shadow of a cutout (one session per object on the layer unless --one-object); returns
    (CanvasShadow, loaded method, what to report: the session's camera_read, and the thickness the outline reads
    as where the artist's geometry was given).
    The light map and AO edits are read first, so a bad one costs no inference."""
    from .ao_edit import AOEditError
    from .framing import EmptyAlphaError
    from .layer_session import open_session
    from .methods import load_method
    from .session import no_shadow_reason

    lights, edits = _light_map(args), _ao_edits(args)
    stage("loading the model")
    with CTRL_C.held():
        loaded = load_method(args.method)
    stage("analysing the cutout")
    try:
        session = open_session(cutout_rgba[..., 3], loaded.method, args.horizon, args.fov, split=not args.one_object)
    except EmptyAlphaError as exc:
        raise NoShadow(f"{args.cutout}: {exc}") from None
    try:
        session.set_ao_edits(edits)
    except AOEditError as exc:
        raise CliError(f"{args.ao_edits or '--ao-strength'}: {exc}") from None
    try:
        session.set_geometry(args.lift, args.thickness)
    except ValueError as exc:
        raise CliError(f"--{exc}") from None
    stage("rendering the shadow")
    shadow = session.render(lights)
    reason = no_shadow_reason(lights, shadow)
    if reason:
        raise NoShadow(reason)
    read_thickness = session.thickness_read if args.lift or args.thickness is not None else None
    return shadow, loaded, (session.camera_read, read_thickness)


def _write_outputs(
    write, cutout: np.ndarray, shadow, args: argparse.Namespace, background: np.ndarray | None, stage: Stages
) -> list[Path]:
    """Stage the layer and the composite through ``write`` (:func:`ssn_engine.imageio.atomic_writes`)."""
    import numpy as np

    from .compositing import composite_image, layer_image

    h, w = cutout.shape[:2]
    written = []
    if args.layer:
        stage("writing the shadow layer")
        written.append(write(args.layer, layer_image(shadow, w, h, args.color, args.opacity)))
    if args.composite:
        stage("writing the composite")
        if background is None:
            background = np.full((h, w, 4), 255, np.uint8)
        written.append(write(args.composite, composite_image(background, cutout, shadow, args.color, args.opacity)))
    return written


def _load_background(args: argparse.Namespace, size: tuple[int, int]) -> np.ndarray | None:
    """The --composite background, checked against the cutout's (width, height) before any inference."""
    from .imageio import load_image

    if not (args.composite and args.background):
        return None
    background, _ = load_image(args.background, args.max_megapixels)
    if (background.shape[1], background.shape[0]) != size:
        raise CliError(
            f"background is {background.shape[1]} x {background.shape[0]}, the cutout {size[0]} x "
            f"{size[1]}: sizes must match"
        )
    return background


def cmd_render(args: argparse.Namespace) -> int:
    from .imageio import atomic_writes

    if not (args.layer or args.composite):
        raise CliError("nothing to write: give --layer and/or --composite")
    if args.background and not args.composite:
        raise CliError(
            "--background is the backdrop of --composite, and the shadow layer has none: add --composite OUT.png "
            "or leave out --background"
        )
    check_paths(
        {"--layer": args.layer, "--composite": args.composite},
        {
            "the cutout": args.cutout,
            "--background": args.background,
            "--light-map": args.light_map,
            "--ao-edits": args.ao_edits,
        },
    )
    stage = Stages()
    try:
        stage("reading the cutout")
        cutout = load_cutout(args)
        stage("reading the background")
        background = _load_background(args, (cutout.shape[1], cutout.shape[0]))
        shadow, loaded, read = _make_shadow(cutout, args, stage)
        with atomic_writes(args.placed) as write:
            written = _write_outputs(write, cutout, shadow, args, background, stage)
    finally:
        stage.close()
    return _report(written, loaded, *read)


def _report(written: list, loaded, camera_read: dict | None, thickness_read: float | None = None) -> int:
    """Say what was written, which method made it, for a call without a camera which one the model read, and
    for a call with the artist's geometry the thickness the outline reads as."""
    for path in written:
        print(f"wrote {path}")
    print(f"method: {loaded.method.name} ({loaded.note})")
    if camera_read is not None:
        print(
            f"camera read from the cutout's outline: --horizon {camera_read['horizon']:.0f} "
            f"--fov {camera_read['fov']:.0f} (give the image's own to correct it)"
        )
    if thickness_read is not None:
        print(f"thickness read from the cutout's outline: {thickness_read:.2f}")
    return EXIT_OK


DEMO_PRESET = "low-sun-left"  # the demo's light: a low sun, so the shadow it casts shows


def cmd_demo(args: argparse.Namespace) -> int:
    from .imageio import atomic_writes
    from .samples import SAMPLE_FILES, pawn_cutout, studio_background

    samples = [str(Path(args.save_samples) / name) for name in SAMPLE_FILES] if args.save_samples else []
    check_folder("--save-samples", args.save_samples)
    check_paths(
        {
            "--out": args.out,
            "--layer": args.layer,
            **dict(zip(("sample cutout", "sample background"), samples, strict=False)),
        },
        {"--light-map": args.light_map, "--ao-edits": args.ao_edits},
    )
    cutout, background = pawn_cutout(), studio_background()
    args.composite, args.cutout = args.out, "the sample pawn"
    stage = Stages()
    try:
        shadow, loaded, read = _make_shadow(cutout, args, stage)
        with atomic_writes(args.placed) as write:
            written = _write_outputs(write, cutout, shadow, args, background, stage)
            # a fresh background: the composite was blended into the first one
            written += [write(path, image) for path, image in zip(samples, (cutout, studio_background()), strict=False)]
    finally:
        stage.close()
    return _report(written, loaded, *read)


def cmd_presets(args: argparse.Namespace) -> int:
    from .host_kit.light_map import PRESETS, preset

    if args.name:
        print(preset(args.name).to_json())
        return EXIT_OK
    for name in PRESETS:
        lights = preset(name)
        print(f"{name:14s} {len(lights)} light{'s' if len(lights) > 1 else ''}")
    return EXIT_OK


def cmd_serve(args: argparse.Namespace) -> int:
    from .loopback import serve_tcp
    from .methods import load_method
    from .worker import serve_stdio

    loaded = load_method(args.method)
    if args.port is None:
        serve_stdio(loaded)
    else:
        serve_tcp(loaded, args.port, idle_timeout=args.idle_timeout)
    return EXIT_OK


def cmd_benchmark(args: argparse.Namespace) -> int:
    from .benchmark import run_benchmark

    run_benchmark(repeats=args.repeats, method=args.method)
    return EXIT_OK


def cmd_soak(args: argparse.Namespace) -> int:
    from .soak import run_soak

    run_soak(requests=args.requests, minutes=args.minutes, method=args.method, seed=args.seed)
    return EXIT_OK


def _host_installer(host: str) -> Any:
    """The host plug-in's installer module (found by entry point: the engine does not import the plug-ins)."""
    from importlib.metadata import entry_points

    found = {ep.name: ep for ep in entry_points(group=PLUGIN_ENTRY_POINTS)}
    try:
        return found[host].load()
    except (KeyError, ImportError) as exc:
        raise CliError(
            f"the {host} plug-in is not part of this installation ({exc!r}); reinstall ssn-shadow with pip",
            EXIT_ERROR,
        ) from None


def cmd_package(args: argparse.Namespace) -> int:
    from .plugin_package import PackageError, package

    if args.wheel and args.requirement:
        raise CliError("give --wheel or --requirement, not both")
    try:
        out = package(_host_installer(args.host), Path(args.out), args.wheel and Path(args.wheel), args.requirement)
    except PackageError as exc:
        raise CliError(str(exc), EXIT_ERROR) from None
    print(f"wrote {out} ({out.stat().st_size / 1e6:.1f} MB)")
    print(f"next: {PACKAGE_STEP[args.host]}")
    return EXIT_OK


PACKAGE_STEP = {
    "krita": "in Krita, Tools > Scripts > Import Python Plugin from File, choose this file, restart Krita, then "
    "press Set up in Settings > Dockers > Soft Shadow",
    "gimp": "unpack this file into GIMP's plug-ins folder (Edit > Preferences > Folders > Plug-ins), restart GIMP, "
    "then press Set up in Filters > Light and Shadow > Soft Shadow (SSN)...",
}


def cmd_install_plugin(args: argparse.Namespace) -> int:
    host_install = _host_installer(args.host)
    dest = Path(args.dest) if args.dest else None
    path = host_install.install(dest=dest, python=args.python, link=args.link)
    print(f"installed the {args.host} plug-in in {path}")
    print(f"next: {NEXT_STEP[args.host]}")
    return EXIT_OK


NEXT_STEP = {
    "krita": "start Krita, tick 'Soft Shadow (SSN)' in Settings > Configure Krita > Python Plugin Manager, "
    "restart Krita, then show the docker with Settings > Dockers > Soft Shadow",
    "gimp": "restart GIMP (it reads plug-ins at start), open an image with a cutout and run "
    "Filters > Light and Shadow > Soft Shadow (SSN)...",
}


def _add_shadow_options(p: argparse.ArgumentParser) -> None:
    from .ao_edit import MAX_STRENGTH
    from .host_kit.light_map import DEFAULT_PRESET, PRESETS
    from .methods import METHOD_NAMES

    light = p.add_mutually_exclusive_group()
    light.add_argument(
        "--preset", default=DEFAULT_PRESET, choices=list(PRESETS), help="light preset (default: %(default)s)"
    )
    light.add_argument("--light-map", metavar="ELM.json", help="light map JSON (see 'ssn-shadow presets NAME')")
    p.add_argument("--color", type=_color, default=(0.0, 0.0, 0.0), help="shadow colour, e.g. #1a1a2e (default black)")
    p.add_argument(
        "--opacity",
        type=_number_in(0.0, 1.0),
        default=defaults.OPACITY,
        help="shadow opacity in [0, 1] (default %(default)s)",
    )
    p.add_argument("--ao-edits", metavar="EDITS.json", help="JSON list of AO edits (docs/protocol.md)")
    p.add_argument(
        "--ao-strength", type=_number_in(0.0, MAX_STRENGTH), help="scale the contact (AO) occlusion; 0 removes it"
    )
    p.add_argument(
        "--method", default="auto", choices=METHOD_NAMES, help="auto: SSN if a model is installed, else geometric"
    )
    p.add_argument(
        "--horizon",
        type=float,
        metavar="ROW",
        help="the image's horizon: canvas row (pixels from the top; may be negative or past the bottom) "
        "where the ground plane meets the sky; default: the camera the model reads from the cutout's outline "
        "(--method geometric: a camera pitched 15 degrees down)",
    )
    p.add_argument(
        "--fov",
        type=_number_in(*FOV_RANGE),
        metavar="DEG",
        help=f"with --horizon: the image's vertical field of view in degrees (default {DEFAULT_FOV:g})",
    )
    p.add_argument(
        "--lift",
        type=_number_in(0.0, math.inf),
        default=0.0,
        metavar="L",
        help="the object floats: canvas rows from its lowest point down to the ground beneath it (default 0: it "
        "rests on the ground; docs/conventions.md, 'Lift and thickness')",
    )
    p.add_argument(
        "--thickness",
        type=_number_in(*THICKNESS_RANGE),
        metavar="T",
        help="the object's depth along the view over its width across it (0 a flat sign, 1 a ball, 2 a person "
        "seen from the side); default: read from the outline",
    )
    p.add_argument(
        "--one-object",
        action="store_true",
        help="cast one shadow from the whole alpha, framed as one object (default: each separate object on the "
        "layer casts its own; docs/engine.md, 'Several objects on one layer')",
    )


def build_parser() -> argparse.ArgumentParser:
    from . import __version__
    from .imageio import DEFAULT_MAX_MEGAPIXELS

    parser = argparse.ArgumentParser(prog="ssn-shadow", description="Soft shadows for 2D cutouts (SSN, CVPR 2021).")
    parser.add_argument("--version", action="version", version=f"ssn-shadow {__version__}")
    sub = parser.add_subparsers(dest="command", required=True, metavar="COMMAND")

    p = sub.add_parser("render", help="make a shadow layer and/or a composite for a cutout PNG")
    p.add_argument("cutout", help="RGBA image; its alpha is the cutout")
    p.add_argument("--layer", metavar="OUT.png", help="write the shadow layer (RGBA, canvas size)")
    p.add_argument("--composite", metavar="OUT.png", help="write cutout + shadow over --background")
    p.add_argument("--background", metavar="BG.png", help="background for --composite (default white)")
    p.add_argument(
        "--whole-image",
        action="store_true",
        help="accept an image without alpha, or opaque everywhere: the whole rectangle casts the shadow",
    )
    p.add_argument(
        "--max-megapixels",
        type=_number_in(0.01, 10000.0),
        default=DEFAULT_MAX_MEGAPIXELS,
        metavar="MP",
        help="refuse larger images (default %(default)g; about 15 bytes a pixel are needed)",
    )
    _add_shadow_options(p)
    p.set_defaults(func=cmd_render)

    p = sub.add_parser("demo", help="render the bundled sample cutout over the bundled background")
    p.add_argument("--out", default="ssn-shadow-demo.png", help="composite PNG (default %(default)s)")
    p.add_argument("--layer", metavar="OUT.png", help="also write the shadow layer")
    p.add_argument(
        "--save-samples",
        metavar="DIR",
        help="also write the sample cutout and background PNGs into this existing folder",
    )
    _add_shadow_options(p)
    p.set_defaults(func=cmd_demo, preset=DEMO_PRESET)

    p = sub.add_parser("presets", help="list light presets, or print one as light-map JSON")
    p.add_argument("name", nargs="?", help="preset to print as JSON")
    p.set_defaults(func=cmd_presets)

    from .methods import METHOD_NAMES

    p = sub.add_parser("serve", help="run the engine worker for the plug-ins (docs/protocol.md)")
    p.add_argument("--port", type=int, help="listen on 127.0.0.1:PORT (0 = any free port) instead of stdin/stdout")
    p.add_argument(
        "--idle-timeout",
        type=float,
        metavar="SECONDS",
        help="with --port: exit after this long without a connection (default: never)",
    )
    p.add_argument("--method", default="auto", choices=METHOD_NAMES)
    p.set_defaults(func=cmd_serve)

    p = sub.add_parser("benchmark", help="time AOP, SR, the geometric method and end to end")
    p.add_argument("--repeats", type=int, default=20, help="timed runs per figure (default %(default)s)")
    p.add_argument("--method", default="auto", choices=METHOD_NAMES)
    p.set_defaults(func=cmd_benchmark)

    p = sub.add_parser("soak", help="run a worker under a long request mix and print its memory over time")
    p.add_argument("--requests", type=int, default=10000, help="requests to send (default %(default)s)")
    p.add_argument("--minutes", type=float, default=0.0, help="run this long instead of --requests")
    p.add_argument("--method", default="auto", choices=METHOD_NAMES)
    p.add_argument("--seed", type=int, default=0)
    p.set_defaults(func=cmd_soak)

    p = sub.add_parser("install-plugin", help="install the Krita or GIMP plug-in for this engine")
    p.add_argument("host", choices=["krita", "gimp"])
    p.add_argument("--dest", help="plug-in folder (default: the host's user folder for this OS)")
    p.add_argument("--python", help="Python that runs the engine (default: this one)")
    p.add_argument("--link", action="store_true", help="symlink instead of copying (for development)")
    p.set_defaults(func=cmd_install_plugin)

    p = sub.add_parser("package", help="build the one file an artist installs from inside Krita or GIMP")
    p.add_argument("host", choices=["krita", "gimp"])
    p.add_argument("--out", required=True, help="the zip to write")
    p.add_argument("--wheel", help="the engine wheel to carry (default: built from this source checkout)")
    p.add_argument("--requirement", help="carry no wheel: Set up installs this from the index (e.g. ssn-shadow==0.2.0)")
    p.set_defaults(func=cmd_package)
    return parser


def main(argv: Sequence[str] | None = None) -> int:
    """Run the CLI; returns the exit status. Ctrl+C at any point, the heavy imports included, ends it with
    status 130 and a line saying which files (if any) were written, without a traceback."""
    placed: list[Path] = []  # the outputs put in place so far (:func:`ssn_engine.imageio.atomic_writes`)
    try:
        return _handling_ctrl_c(argv, placed)
    except KeyboardInterrupt:  # from the command, or as the handler is put back when it has ended
        what = "wrote " + ", ".join(map(str, placed)) if placed else "nothing written"
        print(f"ssn-shadow: interrupted, {what}", file=sys.stderr)
        return EXIT_INTERRUPTED


def _handling_ctrl_c(argv: Sequence[str] | None, placed: list[Path]) -> int:
    """:func:`_run` with :data:`CTRL_C` as the SIGINT handler (in the main thread, the only one signals reach)."""
    if threading.current_thread() is not threading.main_thread():
        return _run(argv, placed)
    previous = signal.signal(signal.SIGINT, CTRL_C)
    try:
        return _run(argv, placed)
    finally:
        # As the program itself (``argv`` from the command line) it exits next, and a Ctrl+C while the
        # interpreter shuts down (onnxruntime's and the stripes' threads end) has nothing left to stop.
        signal.signal(signal.SIGINT, signal.SIG_IGN if argv is None else previous)


def _run(argv: Sequence[str] | None, placed: list[Path]) -> int:
    with CTRL_C.held():  # numpy's C extension imports Python modules as it loads: an interrupt there is an ImportError
        parser = build_parser()
        from .imageio import ImageFileError
        from .host_kit.light_map import LightMapError
        from .methods import ModelError
    args = parser.parse_args(argv)
    args.placed = placed

    try:
        return args.func(args)
    except NoShadow as exc:
        print(f"ssn-shadow: no visible shadow: {exc}; nothing was written", file=sys.stderr)
        return EXIT_NO_SHADOW
    except CliError as exc:
        print(f"ssn-shadow: error: {exc}", file=sys.stderr)
        return exc.code
    except (ImageFileError, LightMapError, ValueError) as exc:
        print(f"ssn-shadow: error: {exc}", file=sys.stderr)
        return EXIT_USAGE
    except ModelError as exc:
        print(f"ssn-shadow: error: {exc}", file=sys.stderr)
        return EXIT_ERROR


if __name__ == "__main__":
    raise SystemExit(main())
