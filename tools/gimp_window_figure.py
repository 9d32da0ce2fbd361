"""docs/img/gimp-window.png: real GIMP 3 in a 1366 x 768 window, an image with a cutout layer, and the Soft Shadow
(SSN) dialog open over it with the image's horizon set (the preview draws the horizon line).

usage: sudo python tools/gimp_window_figure.py [--out docs/img/gimp-window.png]

Needs root and the GIMP 3 chroot (sudo tools/gimp_chroot.sh build). Like the integration test
(tests/plugin_gimp/test_gimp_integration.py), this script starts an engine worker on a loopback port (the test's
loopback_worker.py), installs the plug-in into a fresh GIMP profile in the chroot's /tmp (its sessionrc: a
1366 x 768 single window) and runs the GIMP GUI on a 1366 x 768 Xvfb screen. There the test's scene
(gimp_pawn_scene.py) is built, this file's
``inside`` shows it in a display zoomed to fit, and the test's gimp_dialog_check.py opens the dialog, whose
self-test hook (SSN_SHADOW_DIALOG_SELFTEST, SSN_SHADOW_SCREEN_SCREENSHOT) edits the light map, turns the horizon
on, moves the dialog to the screen's top-right corner and grabs the screen.
"""

from __future__ import annotations

import os
import sys
import time
from pathlib import Path

SCREEN = (1366, 768)
RIGHT_DOCKS_WIDTH = 600  # about the dialog's width: the dialog covers the docks, the canvas stays in view


def inside(image) -> None:  # pragma: no cover - runs in GIMP's python-fu-eval, in the chroot
    """Show ``image`` in a display and zoom it to fit the canvas (Shift+Ctrl+J, pressed with xdotool); then move
    the pointer off the canvas (the paintbrush's outline would show there) to the empty Layers panel below where
    the dialog opens (over the dialog it would raise a tooltip)."""
    import subprocess

    import gi

    gi.require_version("Gimp", "3.0")
    from gi.repository import Gimp

    def xdotool(*args: str) -> str:
        return subprocess.run(["xdotool", *args], capture_output=True, text=True, timeout=20).stdout

    image.clean_all()
    Gimp.Display.new(image)
    Gimp.displays_flush()
    for _ in range(40):  # the image window's title lists its layers
        found = xdotool("search", "--onlyvisible", "--name", r"\[Untitled\].*layers").split()
        if found:
            xdotool("windowfocus", "--sync", found[0])
            time.sleep(0.3)
            xdotool("key", "--clearmodifiers", "shift+ctrl+j")  # View > Zoom > Fit Image in Window
            xdotool("mousemove", str(SCREEN[0] - RIGHT_DOCKS_WIDTH // 2), str(SCREEN[1] - 80))
            break
        time.sleep(0.25)
    else:
        print("figure: no image window found", file=sys.stderr, flush=True)
    time.sleep(1.0)


def write_profile(profile: Path, chroot: Path) -> None:
    """GIMP's settings for the figure: the shipped sessionrc with a 1366 x 768 single window, and no welcome."""
    session = (chroot / "etc" / "gimp" / "3.0" / "sessionrc").read_text()
    for old, new in (
        ("(size 800 600)", f"(size {SCREEN[0]} {SCREEN[1]})"),
        ('(right-docks-width "205")', f'(right-docks-width "{RIGHT_DOCKS_WIDTH}")'),
    ):
        if old not in session:
            raise SystemExit(f"the chroot's sessionrc has no {old}: update {Path(__file__).name}")
        session = session.replace(old, new, 1)
    (profile / "sessionrc").write_text(session + "(single-window-mode yes)\n")
    (profile / "gimprc").write_text("(show-welcome-dialog no)\n(check-updates no)\n")


def run_gimp(tool: Path, inner: str, shot: str) -> tuple[str, float]:
    """The GIMP GUI on a 1366 x 768 Xvfb screen: the scene, the display, the dialog. Returns its log and seconds."""
    import subprocess

    code = (
        f'SCENE_PRECISION = ""; exec(open("{inner}/scene.py").read()); '
        f'import sys; sys.path.insert(0, "{inner}"); import {Path(__file__).stem} as figure; figure.inside(image); '
        f'OUT_PATH = "{inner}/out/dialog.json"; exec(open("{inner}/dialog.py").read())'
    )
    env = {
        **os.environ,
        "SSN_GIMP3_DIRECTORY": f"{inner}/profile",
        "SSN_GIMP_GUI": "1",
        "SSN_GIMP_SCREEN": f"{SCREEN[0]}x{SCREEN[1]}x24",
        "SSN_SHADOW_DIALOG_SELFTEST": "1",
        "SSN_SHADOW_SCREEN_SCREENSHOT": shot,
    }
    start = time.monotonic()
    try:
        run = subprocess.run([str(tool), "gimp-eval", code], env=env, capture_output=True, text=True, timeout=300)
        log = run.stdout + run.stderr
    except subprocess.TimeoutExpired as exc:
        log = f"{exc.stdout or ''}{exc.stderr or ''}\n(GIMP timed out)"
    return log, time.monotonic() - start


def main(argv: list[str] | None = None) -> int:
    import argparse
    import shutil
    import subprocess
    import tempfile

    repo = Path(__file__).resolve().parents[1]
    sys.path.insert(0, str(repo))
    from plugin_gimp.install import install

    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    p.add_argument("--out", default="docs/img/gimp-window.png")
    args = p.parse_args(argv)
    out = Path(args.out).resolve()
    tool = repo / "tools" / "gimp_chroot.sh"
    tests = repo / "tests" / "plugin_gimp"
    if os.geteuid() != 0:
        raise SystemExit("needs root (chroot and mount): sudo python tools/gimp_window_figure.py")
    status = subprocess.run([str(tool), "status"], capture_output=True, text=True)
    if status.returncode != 0:
        raise SystemExit(f"no GIMP 3 chroot ({status.stdout.strip()}): sudo tools/gimp_chroot.sh build")
    chroot = Path(status.stdout.split(None, 1)[1].strip())
    sys.path.insert(0, str(tests))
    from loopback_worker import loopback_worker  # the integration test's worker

    work = Path(tempfile.mkdtemp(prefix="ssn-gimp-figure-", dir=chroot / "tmp"))
    inner = "/tmp/" + work.name  # the same folder seen from inside the chroot
    try:
        with loopback_worker(repo) as (port, token):
            install(work / "profile" / "plug-ins" / "ssn-shadow", address=("127.0.0.1", port), token=token)
            write_profile(work / "profile", chroot)
            (work / "out").mkdir()
            shutil.copy(tests / "gimp_pawn_scene.py", work / "scene.py")
            shutil.copy(tests / "gimp_dialog_check.py", work / "dialog.py")
            shutil.copy(__file__, work / Path(__file__).name)
            log, seconds = run_gimp(tool, inner, inner + "/out/screen.png")
        said = "\n".join(ln for ln in log.splitlines() if "selftest" in ln or "figure:" in ln or "rror" in ln)
        if not (work / "out" / "screen.png").exists():
            raise SystemExit(f"GIMP wrote no picture:\n{said or log[-3000:]}")
        shutil.copy(work / "out" / "screen.png", out)
    finally:
        shutil.rmtree(work, ignore_errors=True)
    print(f"{said}\nwrote {out} (GIMP session {seconds:.1f} s)", file=sys.stderr)
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
