"""Benchmark the Krita docker in real Krita: the live preview's updates per second while a light is dragged on
a 2000 x 2000 canvas (a Gaussian light the network renders, and a 0.53-degree sun traced), the time from the
release to the written layer, and the time from Generate to a visible layer on a 4000 x 3000 canvas.

``python -m plugin_krita.benchmark [--load N]`` (needs Debian's krita: kritarunner); ``--load N`` runs N
busy processes beside Krita meanwhile, a competing CPU load.
"""

from __future__ import annotations

import argparse
import contextlib
import json
import os
import random
import shutil
import subprocess
import sys
import tempfile
from pathlib import Path

from .install import install

ROOT = (
    Path(__file__).resolve().parents[1]
)  # the folder holding plugin_krita and ssn_engine: a checkout or site-packages
DRIVER = Path(__file__).with_name("bench_driver.py")  # runs inside Krita (kritarunner -s), shipped with the package


BUSY = "while True: pass"  # one competing process: a core's worth of load


@contextlib.contextmanager
def competing_load(processes: int):
    """``processes`` busy Python processes while the block runs."""
    busy = [subprocess.Popen([sys.executable, "-c", BUSY]) for _ in range(processes)]
    try:
        yield
    finally:
        for proc in busy:
            proc.kill()
            proc.wait()


def run(drag_s: float = 8.0, load: int = 0) -> dict:
    kritarunner = shutil.which("kritarunner")
    if kritarunner is None:
        raise SystemExit("kritarunner not found: apt-get install krita")
    with tempfile.TemporaryDirectory() as tmp:
        pykrita = install(Path(tmp) / "pykrita", python=sys.executable).parent
        result = Path(tmp) / "bench.json"
        env = dict(os.environ)
        env.update(
            SSN_BENCH_RESULT=str(result),
            SSN_BENCH_DRAG_S=str(drag_s),
            PYTHONPATH=os.pathsep.join([str(pykrita), str(DRIVER.parent), str(ROOT)]),
            PATH=os.pathsep.join(["/usr/bin", "/bin", env.get("PATH", "")]),  # Krita's own python3 first
        )
        env.pop("SSN_SHADOW_ENGINE_CONFIG", None)
        env.pop("QT_QPA_PLATFORM", None)
        xvfb = shutil.which("xvfb-run")  # Krita's windows need an X server (apt-get install xvfb)
        if xvfb is None:
            raise SystemExit("xvfb-run not found: apt-get install xvfb")
        with competing_load(load):
            proc = subprocess.run(
                # a random first display number: an X server in another mount namespace may hold a low one
                [xvfb, "-a", "-n", str(random.randint(200, 900)), kritarunner, "-s", DRIVER.stem, "-f", "main"],
                env=env,
                capture_output=True,
                text=True,
                timeout=600,
            )
        if not result.exists():
            raise SystemExit(f"Krita wrote no result:\n{proc.stdout[-2000:]}\n{proc.stderr[-2000:]}")
        return json.loads(result.read_text())


def main() -> None:
    parser = argparse.ArgumentParser(
        prog="python -m plugin_krita.benchmark", description=(__doc__ or "").split("\n\n")[0]
    )
    parser.add_argument("--load", type=int, default=0, metavar="N", help="busy processes beside Krita (default 0)")
    args = parser.parse_args()
    data = run(load=args.load)
    if "error" in data:
        raise SystemExit(data["error"])
    print(f"competing load: {args.load} busy processes")
    print("a light dragged on a 2000 x 2000 U8 canvas (60 Hz mouse moves): the docker's live preview")
    print(
        f"{'light':10s} {'previews/s':>10s} {'median gap ms':>13s} {'worker ms':>9s} {'round trip ms':>13s} "
        f"{'preview px':>10s}"
    )
    for light, p in data["previews"].items():
        size = " ".join("x".join(map(str, wh)) for wh in p["preview_sizes"])
        print(
            f"{light:10s} {p['previews_per_s']:10.1f} {p['median_preview_gap_ms']!s:>13s} "
            f"{p['median_worker_ms']!s:>9s} {p['median_round_trip_ms']!s:>13s} {size:>10s}"
        )
    print(
        "medians; worker: its render of a preview (the shadow on the thumbnail, the composite); round trip: the "
        "request to the reply's last byte in Krita; preview px: the preview's size (the docker's preview at its "
        "preferred width)"
    )
    gen = data["generate_4000x3000_ms"]
    u8 = data["live"].get("U8", {}).get("release_to_layer_ms")
    print("a light dragged on a 2000 x 2000 canvas (60 Hz mouse moves): the docker's live preview, then the layer")
    print(
        f"{'depth':6s} {'previews/s':>10s} {'median gap ms':>13s} {'layer writes':>12s} {'release to layer ms':>19s} "
        f"{'vs U8':>6s} {'stall ms':>8s} {'drag start ms':>13s} {'re-read ms':>10s}"
    )
    for depth, live in data["live"].items():
        ms = live["release_to_layer_ms"]
        ratio = f"{ms / u8:.2f}" if u8 and ms else "-"
        print(
            f"{depth:6s} {live['previews_per_s']:10.1f} {live['median_preview_gap_ms']!s:>13s} "
            f"{live['layer_writes_during_drag']:12d} {ms!s:>19s} {ratio:>6s} "
            f"{live['release_longest_stall_ms']!s:>8s} {live['drag_start_ms']!s:>13s} "
            f"{live.get('drag_reread_ms')!s:>10s}"
        )
    print("where a release's time goes (medians, ms)")
    parts = [
        ("queued", "request_after"),
        ("waiting", "waiting"),
        ("worker", "worker"),
        ("shadow", "worker_shadow"),
        ("layer", "worker_layer"),
        ("reply", "reply_transfer"),
        ("after", "after_reply"),
        ("write", "write"),
    ]
    print(f"{'depth':6s} " + " ".join(f"{label:>7s}" for label, _ in parts) + f" {'reads':>5s} {'MB':>6s}")
    for depth, live in data["live"].items():
        print(
            f"{depth:6s} "
            + " ".join(f"{live[f'release_{key}_ms']!s:>7s}" for _, key in parts)
            + f" {live['release_reply_chunks']!s:>5s} {live['release_layer_mb']!s:>6s}"
        )
    print(
        f"release: medians of {data['live'][next(iter(data['live']))]['releases']} releases after short drags; "
        "stall: the longest the event loop did not turn from the release to the written layer; drag start: "
        "Krita's part of a drag's start (its undo step, the shadow layer replaced by a copy of itself, and the "
        "preview's background, taken again only where the image changed); re-read: the cutout read again before it "
        "(only where an undoable change was made since it was read). queued: release to the render request; "
        "waiting: the request to the reply's first "
        "byte less the render (a preview still in flight at the release, the worker reading the request and "
        "writing the reply); worker: its render, of which shadow (the shadow at the canvas's size: the network, "
        "and the traced lights on a thread beside it) and layer (the layer's pixels in the document's format); "
        "reply: the reply's first to last "
        "byte in Krita, in that many reads; after: the reply's last byte to the written layer less Krita's write "
        "(decoding, dispatch); write: Krita's part (the layer written in place); MB: the layer's bytes"
    )
    print(
        f"Generate to visible layer, 4000 x 3000 canvas: median {sorted(gen)[len(gen) // 2]:.0f} ms "
        f"(runs: {', '.join(f'{t:.0f}' for t in gen)} ms; full path: read alpha, AO, render, write)"
    )


if __name__ == "__main__":
    main()
