"""training.data.packed: a dataset's masks and AO maps in one small file, read as a store by an AOP's training."""

from __future__ import annotations

import sys
from pathlib import Path

import numpy as np
import pytest

sys.path.insert(0, str(Path(__file__).parent))
from test_train_standin import FakeStore, tiny_run_args  # noqa: E402

from training.batches import load_view  # noqa: E402
from training.data.packed import PackedStore, pack  # noqa: E402

pytest.importorskip("torch")


@pytest.fixture
def packed(tmp_path):
    store = FakeStore(res=32)
    path = tmp_path / "views.npz"
    assert pack(store, 16, path) == len(store)
    return store, path


def test_a_packed_view_is_the_view_an_aop_trains_on(packed):
    """The same splits and kinds; each view's mask, AO map and camera input, as the training loop loads them at the
    packed resolution, equal the full store's to 8 bits (the camera exactly: it is rescaled to the smaller frame)."""
    store, path = packed
    small = PackedStore(path)
    assert small.meta["res"] == 16 and small.view_ids("val", "object") == store.view_ids("val", "object")
    for i in store.view_ids(None):
        full, mine = load_view(store, i, 16, with_occ=False), load_view(small, i, 16, with_occ=False)
        assert mine.key == full.key
        np.testing.assert_allclose(mine.mask, full.mask, atol=0.5 / 255 + 1e-6)
        np.testing.assert_allclose(mine.ao, full.ao, atol=0.5 / 255 + 1e-6)
        np.testing.assert_allclose(mine.camera, full.camera, rtol=1e-9)


def test_an_aop_trains_from_the_file_and_an_sr_is_refused(packed, tmp_path):
    from training.train import main

    _, path = packed
    common = ["--data", str(path), "--steps", "2", *tiny_run_args(16, 1)]
    assert main(["--module", "aop", "--run", str(tmp_path / "aop"), *common]) == 0
    assert (tmp_path / "aop" / "last.pt").is_file()
    # the camera-taking AOP too (training/gpu_aop.sh runs it from such a file): the infos carry the rescaled camera
    assert main(["--module", "aop", "--camera", "--run", str(tmp_path / "aop_camera"), *common]) == 0
    assert (tmp_path / "aop_camera" / "last.pt").is_file()
    with pytest.raises(SystemExit):
        main(["--module", "sr", "--run", str(tmp_path / "sr"), *common])
    with pytest.raises(ValueError, match="AOP"):
        PackedStore(path).load(0)
