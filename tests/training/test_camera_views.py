"""The camera estimator's data (training.data.camera_views): what a view records."""

from __future__ import annotations

import numpy as np

from training.data import meshes
from training.data.camera_views import R, view_record
from training.data.procedural import box


def test_a_view_record_describes_the_view():
    """A box standing on the ground seen from above: its mask at R covers it, the horizon lies above its base, and
    the estimator's input and target are made in the canonical frame."""
    mesh = meshes.normalise(box((0.5, 0.35, 0.3), (0.0, 0.175, 0.0)))
    view = view_record(mesh, meshes.topology(mesh), 0.0, 15.0, 45.0)
    covered = view["mask"] > 0.5
    assert view["mask"].shape == (R, R)
    assert covered.sum() > 100
    horizon, focal = view["camera"]
    assert horizon < np.flatnonzero(covered.any(axis=1))[-1]  # looking down: the horizon above the base
    assert focal > 0
    assert view["estimator"].ndim == 2 and 0.0 <= view["estimator"].min() <= view["estimator"].max() <= 1.0
    assert view["estimator_camera"].shape == (2,)
