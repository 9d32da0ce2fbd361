"""Train batches built ahead in a background thread (numpy releases the GIL) while the model trains."""

from __future__ import annotations

import contextlib
import queue
import threading

import numpy as np
import torch

from .batches import BatchSampler

__all__ = ["BatchStream", "Prefetcher"]


class Prefetcher:
    """Builds batches in a background thread (numpy releases the GIL) while the model trains."""

    def __init__(self, make, rng: np.random.Generator, depth: int = 2):
        self.make, self.rng = make, rng
        self.q: queue.Queue = queue.Queue(maxsize=depth)
        self.stop = False
        self.thread = threading.Thread(target=self._run, daemon=True)
        self.thread.start()

    def _run(self) -> None:
        while not self.stop:
            try:
                item = self.make(self.rng)
            except Exception as exc:  # hand the error to the consumer
                item = exc
            self.q.put(item)
            if isinstance(item, Exception):
                return

    def next(self):
        item = self.q.get()
        if isinstance(item, Exception):
            raise item
        return item

    def close(self) -> None:
        """Stop and join the thread: left running in native code at interpreter exit, it can abort the process
        ("terminate called without an active exception"), and a restarted stream must not share the sampler."""
        self.stop = True
        while self.thread.is_alive():
            with contextlib.suppress(queue.Empty):
                self.q.get(timeout=0.05)  # frees a put the thread may be blocked on
        self.thread.join()


class BatchStream:
    """This process's train batches, built ahead in a thread, and the generator of the AO augmentation.

    Both are seeded from --seed, the rank and the step, so a resumed run is reproducible given where it stopped.
    """

    def __init__(self, sampler: BatchSampler, seed: int, rank: int, step: int):
        self.sampler, self.seed, self.rank = sampler, seed, rank
        self.gen = torch.Generator().manual_seed(seed * 1000 + rank + step)
        self.start(step)

    def start(self, step: int) -> None:
        """(Re)start the prefetcher on a batch stream seeded from ``step``."""
        self.pre = Prefetcher(self.sampler, np.random.default_rng([self.seed, self.rank, step]))

    def next(self):
        return self.pre.next()

    def close(self) -> None:
        self.pre.close()
