"""The conventions' metrics."""

from __future__ import annotations

import numpy as np
import pytest

from training.metrics import all_metrics, dssim, mean_metrics, rmse, rmse_s, zncc


def test_rmse():
    assert rmse(np.zeros((4, 4)), np.full((4, 4), 0.5)) == pytest.approx(0.5)


def test_rmse_s_is_the_optimal_scale():
    rng = np.random.default_rng(0)
    p, g = rng.random((16, 16)), rng.random((16, 16))
    brute = min(rmse(k * p, g) for k in np.linspace(0, 2, 20001))
    assert rmse_s(p, g) == pytest.approx(brute, abs=1e-6)
    assert rmse_s(0.5 * g, g) == pytest.approx(0.0, abs=1e-12)
    assert rmse_s(np.zeros((3, 3)), g[:3, :3]) == pytest.approx(rmse(0 * g[:3, :3], g[:3, :3]))


def test_zncc_and_its_constant_image_rule():
    rng = np.random.default_rng(1)
    g = rng.random((8, 8))
    assert zncc(2 * g + 1, g) == pytest.approx(1.0)
    assert zncc(-g, g) == pytest.approx(-1.0)
    assert zncc(np.zeros((8, 8)), np.zeros((8, 8))) == 1.0
    assert zncc(np.zeros((8, 8)), g) == 0.0
    assert zncc(np.ones((8, 8)), np.zeros((8, 8))) == 0.0


def test_dssim():
    rng = np.random.default_rng(2)
    g = rng.random((32, 32))
    assert dssim(g, g) == pytest.approx(0.0, abs=1e-12)
    assert 0 < dssim(np.zeros((32, 32)), g) <= 1


def test_all_and_mean():
    g = np.random.default_rng(3).random((16, 16))
    rows = [all_metrics(g, g), all_metrics(np.zeros_like(g), g)]
    m = mean_metrics(rows)
    assert m["RMSE"] == pytest.approx(rows[1]["RMSE"] / 2)
    assert m["ZNCC"] == pytest.approx(0.5)
