"""The project's docs/conventions.md, the code and (where the workspace has it) the external contract agree on
the numbers: the frame, the object's top row, the ELM grid, the default camera and the camera input."""

from __future__ import annotations

import math
from pathlib import Path

import pytest

from ssn_engine import camera, framing
from ssn_engine.host_kit import camera_rules, sky_map
from ssn_engine.methods import load_method

REPO = Path(__file__).resolve().parents[2]
OURS = (REPO / "docs" / "conventions.md").read_text()
SHARED = REPO.parent / "shared" / "docs" / "conventions.md"


def test_the_code_keeps_the_numbers():
    assert load_method("ssn").method.resolution == 256  # the shipped model
    assert camera.top_row(256) == round(0.03 * 256) == 8
    assert sky_map.NETWORK_SHAPE == (16, 32)
    assert camera.DISTANCE == 2.0 and camera_rules.DEFAULT_FOV == 45.0 and camera.DEFAULT_PITCH == 15.0
    assert framing.OBJECT_EXTENT == 0.5
    f = camera.focal_from_fov(256, 50.0)
    assert math.isclose(f, 128 / math.tan(math.radians(25.0)))
    assert math.isclose(camera.horizon_row(256, f, 20.0, 7.0), 128 - f * math.tan(math.radians(20.0)) + 7.0)


@pytest.mark.parametrize(
    "fact",
    [
        "**N = 256**",
        "round(0.03 N) = 8",
        "**16 x 32**",
        "**distance 2**",
        "**45 degree**",
        "**15 degree**",
        "**f = (N / 2) / tan(fov / 2)**",
        "**h = N/2 - f tan(pitch) + shift**",
        "h = k H + d and f = k F",
        "`OBJECT_EXTENT = 0.5`",
        "**A^(1/3)**",
        "**s = 1 - E / E0**",
    ],
)
def test_our_page_states_them(fact):
    assert fact in OURS


@pytest.mark.skipif(not SHARED.exists(), reason="the external contract is not in this workspace")
@pytest.mark.parametrize(
    "fact",
    [
        "N = 256",
        "row 8 at N = 256",
        "round(0.03 N)",
        "16 x 32",
        "from\n  distance 2",
        "f = (N / 2) / tan(fov / 2)",
        "h = N/2 - f tan(pitch) + shift",
        "h = k H + d and f = k F",
        "A^(1/3)",
        "s(x) = 1 - E(x) / E0",
    ],
)
def test_the_external_contract_says_the_same(fact):
    assert fact in SHARED.read_text()
