"""A worker under a long, mixed request stream keeps its memory flat (ssn-shadow soak, short)."""

import io

from ssn_engine.soak import run_soak
from ssn_engine.worker import TRIM_THRESHOLD


def test_worker_memory_stays_flat_over_many_requests():
    out = io.StringIO()
    figures = run_soak(requests=500, method="geometric", out=out)
    assert figures["requests"] == 500
    # Sessions of different canvas sizes come and go (up to 8 kept), so RSS moves by tens of MiB, and the worker's
    # heap keeps up to TRIM_THRESHOLD of freed memory for the next request (tune_malloc); a leak of one
    # canvas-sized buffer per render (a 1600 x 1200 float32 canvas is 7 MiB) would add hundreds.
    assert figures["growth_mib"] < TRIM_THRESHOLD / 2**20 + 16, out.getvalue()
    assert "growth" in out.getvalue()
