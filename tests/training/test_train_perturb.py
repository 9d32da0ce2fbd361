"""AO perturbation: grey erosion or dilation, never both, keeps the range."""

from __future__ import annotations

import pytest

torch = pytest.importorskip("torch")

from training.perturb import perturb_ao  # noqa: E402


def test_perturbation_is_erosion_dilation_or_identity():
    g = torch.Generator().manual_seed(0)
    ao = torch.rand(32, 1, 24, 24)
    out = perturb_ao(ao, g)
    kinds = set()
    for b in range(32):
        if torch.equal(out[b], ao[b]):
            kinds.add("same")
        elif bool((out[b] <= ao[b]).all()):
            kinds.add("eroded")
        elif bool((out[b] >= ao[b]).all()):
            kinds.add("dilated")
        else:
            raise AssertionError("neither erosion nor dilation")
    assert kinds == {"same", "eroded", "dilated"}
    assert out.min() >= 0 and out.max() <= 1 and out.shape == ao.shape
