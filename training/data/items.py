"""One shape of a dataset (:class:`Item`) and the helpers that order and split them; the sources
(:mod:`training.data.sources`, ``procedural``, ``humans``) all build on this module."""

from __future__ import annotations

import zlib
from dataclasses import asdict, dataclass, field


@dataclass
class Item:
    """One shape: id, split, kind, category, source and what rebuilds its mesh."""

    id: str
    split: str
    kind: str
    category: str
    source: str
    params: dict = field(default_factory=dict)

    def record(self) -> dict:
        return asdict(self)


def stable_hash(text: str) -> int:
    return zlib.crc32(text.encode())


def item_seed(seed: int, index: int) -> int:
    """The seed of a generated source's ``index``-th item in the set of ``seed`` (each set's items distinct)."""
    return int(seed) * 100003 + index


def split_for(index: int) -> str:
    """80/10/10 split of generated shapes by their index (split by shape, never by view)."""
    r = index % 10
    return "val" if r == 8 else "test" if r == 9 else "train"
