"""When the docker's requests go out: renders coalesced (latest wins), one in flight at a time."""

from __future__ import annotations

from dataclasses import dataclass

__all__ = ["Drag", "LatestWins", "RenderJob", "RenderQueue"]


@dataclass
class RenderJob:
    """One wanted render; ``new_step`` makes its layer write an undo step, ``reread`` re-reads the source (the
    active layer or selection); ``refresh``: reads the same source again first, where its pixels may have changed
    since it was read (an edit's first render); ``retried``: it already sent the cutout again once (after a
    worker restart)."""

    new_step: bool
    reread: bool
    started: float = 0.0
    retried: bool = False
    refresh: bool = False

    def merge(self, other: RenderJob) -> RenderJob:
        return RenderJob(
            self.new_step or other.new_step,
            self.reread or other.reread,
            self.started or other.started,
            refresh=self.refresh or other.refresh,
        )


@dataclass
class Drag:
    """A light drag in progress: the preview's background ((width, height, RGBA), None when there is no
    preview) and whether the drag has its undo step yet (the shadow layer taken over at its start, or written at
    a rest): its writes then go in place."""

    background: tuple[int, int, bytes] | None
    wrote: bool = False


class RenderQueue:
    """At most one render in flight; the jobs wanted meanwhile merge into one pending job."""

    def __init__(self) -> None:
        self.in_flight = False
        self.pending: RenderJob | None = None

    def submit(self, job: RenderJob) -> RenderJob | None:
        """The job to run now, or None when one is in flight (``job`` then waits, merged)."""
        if self.in_flight:
            self.pending = job if self.pending is None else self.pending.merge(job)
            return None
        return job

    def start(self) -> None:
        self.in_flight = True

    def finish(self) -> RenderJob | None:
        """The render in flight is answered: the job that waited, to run next (or None)."""
        job, self.pending = self.pending, None
        self.in_flight = False
        return job

    def clear(self) -> None:
        self.in_flight, self.pending = False, None


class LatestWins:
    """One request of a kind in flight; those wanted meanwhile become one, sent (with the state of that moment)
    when the reply comes."""

    def __init__(self) -> None:
        self.in_flight = False
        self.pending = False

    def begin(self) -> bool:
        """True: send now; False: one is in flight, this one waits."""
        if self.in_flight:
            self.pending = True
            return False
        self.in_flight, self.pending = True, False
        return True

    def end(self) -> bool:
        """The reply came: True when another is wanted (send it now)."""
        again, self.in_flight, self.pending = self.pending, False, False
        return again

    def clear(self) -> None:
        self.in_flight = self.pending = False
