"""A worker under a long, mixed request stream keeps its memory flat (ssn-shadow soak, short)."""

import io

from ssn_engine.soak import run_soak


def test_worker_memory_stays_flat_over_many_requests():
    out = io.StringIO()
    figures = run_soak(requests=500, method="geometric", out=out)
    assert figures["requests"] == 500
    # Sessions of different canvas sizes come and go (up to 8 kept), so RSS moves by tens of MiB; a leak of
    # one canvas-sized buffer per render (a 1600 x 1200 float32 canvas is 7 MiB) would add hundreds.
    assert figures["growth_mib"] < 40, out.getvalue()
    assert "growth" in out.getvalue()
