"""Row stripes: every row once, the same pixels on one thread or several, errors reach the caller."""

from __future__ import annotations

import threading

import numpy as np
import pytest

from ssn_engine import stripes
from ssn_engine.compositing import layer_image, shadow_layer
from ssn_engine.framing import frame_alpha, shadow_to_canvas


def test_every_row_is_done_once_across_threads(monkeypatch: pytest.MonkeyPatch) -> None:
    monkeypatch.setattr(stripes, "THREADS", 2)
    counts = np.zeros(5000, np.int32)
    names: set[str] = set()

    def work(rows: slice) -> None:
        counts[rows] += 1
        names.add(threading.current_thread().name)

    stripes.for_each_stripe(work, 7, 4993, 600)
    assert counts[:7].sum() == 0 and counts[4993:].sum() == 0
    assert (counts[7:4993] == 1).all()
    assert any(n.startswith("ssn-stripes") for n in names)


def test_a_failing_stripe_raises_in_the_caller(monkeypatch: pytest.MonkeyPatch) -> None:
    monkeypatch.setattr(stripes, "THREADS", 2)

    def work(rows: slice) -> None:
        if rows.start > 0:
            raise ValueError("bad stripe")

    with pytest.raises(ValueError, match="bad stripe"):
        stripes.for_each_stripe(work, 0, 4000, 1000)


def test_stripes_inside_stripes_do_not_wait_on_the_pool(monkeypatch: pytest.MonkeyPatch) -> None:
    monkeypatch.setattr(stripes, "THREADS", 2)
    out = np.zeros((3000, 1000), np.int32)

    def outer(rows: slice) -> None:
        def inner(sub: slice) -> None:
            out[sub] += 1

        stripes.for_each_stripe(inner, rows.start, rows.stop, 10)  # many small inner stripes

    stripes.for_each_stripe(outer, 0, 3000, 1000)
    assert (out == 1).all()


def test_threads_give_the_same_canvas_shadow_and_layers(monkeypatch: pytest.MonkeyPatch) -> None:
    """A big canvas resampled and filled on one thread and on four: bit-identical results."""
    alpha = np.zeros((3000, 4000), np.uint8)
    alpha[1200:2600, 1700:2300] = 255
    mask, framing = frame_alpha(alpha, 256)
    yy, xx = np.mgrid[0:256, 0:256]
    frame = np.clip(1.2 - np.hypot(xx - 128, yy - 200) / 120, 0, 1).astype(np.float32) * (mask < 0.5)
    results = []
    for threads in (1, 4):
        monkeypatch.setattr(stripes, "THREADS", threads)
        canvas = shadow_to_canvas(frame, framing)
        results.append(
            (
                canvas.values,
                shadow_layer(canvas.values, (0.2, 0.1, 0.3), 0.8, "uint16", "bgra"),
                layer_image(canvas, 4000, 3000, (0.2, 0.1, 0.3), 0.8),
            )
        )
    assert results[0][0].size > 4 * stripes.STRIPE_PIXELS  # several stripes
    for single, threaded in zip(*results, strict=True):
        np.testing.assert_array_equal(single, threaded)
