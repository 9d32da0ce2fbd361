"""Canvas-sized work a band of rows at a time, on the machine's cores.

A light change resamples and fills a layer of several megapixels. Done in row stripes, its temporaries follow
the stripe, not the canvas; and numpy's and Pillow's loops release the GIL, so stripes run in parallel threads.
"""

from __future__ import annotations

import concurrent.futures
import os
import threading
from collections.abc import Callable, Iterator

STRIPE_PIXELS = 1 << 18  # canvas pixels made at once: temporaries follow this, not the canvas
THREADS = max(1, min(4, os.cpu_count() or 1))
_PREFIX = "ssn-stripes"
_pools: dict[str, concurrent.futures.ThreadPoolExecutor] = {}
_pools_lock = threading.Lock()


def row_stripes(y0: int, y1: int, width: int) -> Iterator[slice]:
    """Consecutive row ranges covering [y0, y1), about STRIPE_PIXELS pixels each."""
    rows = max(1, STRIPE_PIXELS // max(1, width))
    for start in range(y0, y1, rows):
        yield slice(start, min(start + rows, y1))


def thread_pool(prefix: str, threads: int) -> concurrent.futures.ThreadPoolExecutor:
    """The process's pool of ``threads`` threads named ``prefix``, made on first use."""
    with _pools_lock:
        if prefix not in _pools:
            _pools[prefix] = concurrent.futures.ThreadPoolExecutor(threads, thread_name_prefix=prefix)
        return _pools[prefix]


def for_each_stripe(work: Callable[[slice], object], y0: int, y1: int, width: int) -> None:
    """``work(rows)`` for every stripe of :func:`row_stripes`, on up to ``THREADS`` threads; each call must
    write only its own rows. Inside a stripe (nested) the stripes run in turn, so a pool never waits on itself."""
    stripes = list(row_stripes(y0, y1, width))
    if len(stripes) < 2 or THREADS < 2 or threading.current_thread().name.startswith(_PREFIX):
        for rows in stripes:
            work(rows)
        return
    for _ in thread_pool(_PREFIX, THREADS).map(work, stripes):  # re-raises the first error of a stripe
        pass
