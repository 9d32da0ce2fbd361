"""Two-process DistributedDataParallel training (gloo on CPU), the way torchrun launches it (env://)."""

from __future__ import annotations

import os
import socket
import sys
from pathlib import Path

import pytest

torch = pytest.importorskip("torch")

HERE = str(Path(__file__).parent)


def _free_port() -> int:
    with socket.socket() as s:
        s.bind(("127.0.0.1", 0))
        return s.getsockname()[1]


def _worker(rank: int, world: int, port: int, run: str) -> None:
    sys.path.insert(0, HERE)
    from test_train_standin import FakeStore

    from training.train import main

    os.environ.update(
        RANK=str(rank), LOCAL_RANK=str(rank), WORLD_SIZE=str(world), MASTER_ADDR="127.0.0.1", MASTER_PORT=str(port)
    )
    argv = [
        "--module",
        "sr",
        "--run",
        run,
        "--steps",
        "3",
        "--resolution",
        "16",
        "--widths",
        "4,8",
        "--groups",
        "2",
        "--batch",
        "2",
        "--val-samples",
        "2",
        "--val-every",
        "3",
        "--threads",
        "1",
        "--warmup",
        "1",
    ]
    assert main(argv, store=FakeStore(res=16)) == 0


@pytest.mark.skipif(not torch.distributed.is_available(), reason="torch.distributed unavailable")
def test_two_process_ddp(tmp_path):
    import torch.multiprocessing as mp

    from training import checkpoint

    run = tmp_path / "ddp"
    mp.spawn(_worker, args=(2, _free_port(), str(run)), nprocs=2, join=True)
    ck = checkpoint.load(run / "last.pt")
    assert ck["step"] == 3 and ck["samples"] == 3 * 2 * 2
