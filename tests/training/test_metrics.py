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


def _streak(angle_deg: float, length: float, n: int = 128) -> tuple[np.ndarray, np.ndarray]:
    """A box standing on row 80 and a shadow streak of ``length`` px from its foot at ``angle_deg``."""
    from training.metrics import contact_point

    mask = np.zeros((n, n), np.float32)
    mask[40:80, 60:68] = 1.0
    x0, y0 = contact_point(mask)
    s = np.zeros((n, n), np.float32)
    a = np.radians(angle_deg)
    for t in np.linspace(0, length, 400):
        x, y = int(x0 + t * np.cos(a)), int(y0 + t * np.sin(a))
        if 0 <= x < n and 0 <= y < n:
            s[max(y - 1, 0) : y + 2, max(x - 1, 0) : x + 2] = 1.0
    return s * (1 - mask), mask


def test_sun_geometry_measures_direction_and_length():
    from training.metrics import sun_geometry

    g, mask = _streak(160.0, 40.0)
    same = sun_geometry(g, g, mask)
    assert same["direction_error"] < 1e-6 and same["length_ratio"] == pytest.approx(1.0)
    longer, _ = _streak(160.0, 60.0)
    assert sun_geometry(longer, g, mask)["length_ratio"] == pytest.approx(1.5, rel=0.1)
    turned, _ = _streak(130.0, 40.0)
    assert sun_geometry(turned, g, mask)["direction_error"] == pytest.approx(30.0, abs=4.0)
    assert sun_geometry(np.zeros_like(g), g, mask) == {"direction_error": 180.0, "length_ratio": 0.0}
    assert sun_geometry(g, np.zeros_like(g), mask) is None  # no true cast shadow: nothing to measure
