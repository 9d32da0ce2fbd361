"""``ssn-shadow soak``: a worker under a long mix of requests, and whether its memory stays flat.

It starts ``ssn-shadow serve`` as the plug-ins do and sends what an artist's session sends (new cutouts of
varied sizes, light drags, AO edits, light-map pictures, releases) mixed with refused requests, then prints the
worker's resident memory over time and its growth after warm-up.
"""

from __future__ import annotations

import random
import sys
import time
from pathlib import Path

import numpy as np

from .host_kit.client import EngineClient, EngineError
from .host_kit.light_map import LightMap
from .host_kit.protocol import Buffer

WARMUP_SHARE = 0.2  # the first share of requests (model and caches filling up) before the reference RSS
WINDOW = 0.2  # RSS compared as medians over windows of this share of the run (sessions come and go)


def rss_mib(pid: int) -> float:
    """Resident memory of process ``pid`` in MiB (Linux /proc; NaN elsewhere)."""
    try:
        for line in Path(f"/proc/{pid}/status").read_text().splitlines():
            if line.startswith("VmRSS:"):
                return int(line.split()[1]) / 1024
    except OSError:
        pass
    return float("nan")


def _alpha(rng: random.Random) -> Buffer:
    """A random blob cutout on a canvas of random size and alpha depth."""
    w, h = rng.randint(64, 1600), rng.randint(64, 1200)
    yy, xx = np.mgrid[:h, :w]
    cx, cy, rx, ry = w * rng.uniform(0.3, 0.7), h * rng.uniform(0.3, 0.6), w * rng.uniform(0.1, 0.3), h * 0.25
    alpha = np.clip(1.5 - ((xx - cx) / rx) ** 2 - ((yy - cy) / ry) ** 2, 0, 1)
    dtype = rng.choice(["uint8", "uint16", "float32"])
    data = (alpha * np.iinfo(dtype).max).astype(dtype) if dtype != "float32" else alpha.astype(np.float32)
    return Buffer(dtype, data.shape, data.tobytes())


def _step(client: EngineClient, rng: random.Random, cutouts: dict[str, tuple[int, ...]]) -> str:
    """One request of the mix; returns its kind. ``cutouts``: the live cutouts' canvas shapes."""
    roll = rng.random()
    if roll < 0.08 or not cutouts:
        alpha = _alpha(rng)
        cutouts[client.request("set_cutout", {"alpha": alpha})[0]["cutout"]] = tuple(alpha.shape)
        return "set_cutout"
    key = rng.choice(list(cutouts))
    light = LightMap.random(rng, max_lights=rng.choice([1, 2, 8])).to_dict()
    kind = "bad request"
    try:
        if roll < 0.7:
            kind = "render"
            client.request(
                "render", cutout=key, light_map=light, format={"dtype": rng.choice(["uint8", "uint16", "float32"])}
            )
        elif roll < 0.8:
            kind = "edit_ao"
            client.request(
                "edit_ao",
                cutout=key,
                edits=[{"op": "brush", "x": rng.random(), "y": rng.random(), "radius": 0.05, "strength": -0.5}],
            )
        elif roll < 0.85:
            kind = "get_ao"
            client.request("get_ao", cutout=key)
        elif roll < 0.9:
            kind = "preview"
            grey = np.full((*cutouts[key], 3), rng.randrange(256), np.uint8)
            client.request(
                "preview", {"background": Buffer("uint8", grey.shape, grey.tobytes())}, cutout=key, light_map=light
            )
        elif roll < 0.95:
            kind = "release"
            client.request("release", cutout=key)
            del cutouts[key]
        elif roll < 0.975:
            client.request("render", cutout=key, light_map={"lights": "none"})  # refused: LightMapError
        else:
            client.request("launch", cutout=key)  # refused: BadRequest
    except EngineError as exc:
        if exc.kind in ("Internal", "WorkerUnavailable"):
            raise
        if exc.kind == "UnknownCutout":  # the worker keeps at most MAX_SESSIONS; older ones are gone
            del cutouts[key]
    return kind


def run_soak(requests: int = 10000, minutes: float = 0.0, method: str = "auto", seed: int = 0, out=sys.stdout) -> dict:
    """Send ``requests`` requests (or run ``minutes``, if given); print RSS over time, then the memory after
    warm-up and at the end (medians over windows of the run) and the latency per kind; return the figures."""
    rng = random.Random(seed)
    client = EngineClient(command=[sys.executable, "-m", "ssn_engine", "serve", "--method", method], timeout=300)
    latency: dict[str, list[float]] = {}
    try:
        client.request("hello")
        assert client._proc is not None  # the hello above started the worker
        pid = client._proc.pid
        start, cutouts, samples, done = time.monotonic(), {}, [], 0
        deadline = start + 60 * minutes if minutes else None
        every = max(1, requests // 400) if deadline is None else 25
        report = max(1, requests // 20) if deadline is None else 500
        print(f"{'requests':>9} {'seconds':>8} {'RSS MiB':>8}", file=out, flush=True)
        while (done < requests) if deadline is None else (time.monotonic() < deadline):
            t = time.perf_counter()
            kind = _step(client, rng, cutouts)
            latency.setdefault(kind, []).append(1e3 * (time.perf_counter() - t))
            done += 1
            if done % every == 0:
                samples.append((done, time.monotonic() - start, rss_mib(pid)))
            if done % report == 0:
                print(f"{done:9d} {samples[-1][1]:8.1f} {samples[-1][2]:8.1f}", file=out, flush=True)
        client.request("shutdown")
    finally:
        client.close()

    def window_median(lo: float) -> float:
        return float(np.median([s[2] for s in samples if lo * done < s[0] <= (lo + WINDOW) * done + 1e-9]))

    figures = {
        "requests": done,
        "seconds": samples[-1][1],
        "rss_warm_mib": window_median(WARMUP_SHARE),
        "rss_end_mib": window_median(1.0 - WINDOW),
        "rss_peak_mib": max(s[2] for s in samples),
    }
    figures["growth_mib"] = figures["rss_end_mib"] - figures["rss_warm_mib"]
    figures["growth_share"] = figures["growth_mib"] / figures["rss_warm_mib"]
    every_request = [ms for values in latency.values() for ms in values]
    figures["latency_ms"] = {
        kind: (float(np.percentile(v, 50)), float(np.percentile(v, 99)), len(v))
        for kind, v in sorted(latency.items()) + [("all", every_request)]
    }
    print(f"\n{'request':12s} {'count':>6} {'p50 ms':>8} {'p99 ms':>8}", file=out)
    for kind, (p50, p99, count) in figures["latency_ms"].items():
        print(f"{kind:12s} {count:6d} {p50:8.1f} {p99:8.1f}", file=out)
    print(
        f"\nmedian RSS just after warm-up {figures['rss_warm_mib']:.1f} MiB, at the end {figures['rss_end_mib']:.1f} "
        f"MiB (growth {figures['growth_mib']:+.1f} MiB, {100 * figures['growth_share']:+.1f} %), peak "
        f"{figures['rss_peak_mib']:.1f} MiB; {done} requests in {figures['seconds']:.0f} s",
        file=out,
        flush=True,
    )
    return figures
