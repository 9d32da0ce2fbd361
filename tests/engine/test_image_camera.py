"""The camera a host remembers with one image (``host_kit.image_camera``): its own, scaled with it, never
another's."""

from __future__ import annotations

import json

import pytest

from ssn_engine.host_kit import camera_rules
from ssn_engine.host_kit.image_camera import NOT_GIVEN, camera_record, recalled_camera


def test_an_image_gets_back_the_camera_it_was_given():
    record = camera_record(True, 380.0, 52.5, 480)
    assert json.loads(record)["format"] == "ssn-shadow-camera" and len(record) < 120
    assert recalled_camera(record, 480) == {"given": True, "horizon": 380.0, "fov": 52.5}
    assert recalled_camera(camera_record(False, 127.0, 37.0, 240), 240) == {
        "given": False,
        "horizon": 127.0,
        "fov": 37.0,
    }


def test_the_row_follows_the_image_when_it_is_scaled():
    """Row 380 of a 640 x 480 image is row 2375 of the image scaled to 4000 x 3000 (whole rows); the field of
    view does not change with the size."""
    record = camera_record(True, 380.0, 45.0, 480)
    assert recalled_camera(record, 3000) == {"given": True, "horizon": 2375.0, "fov": 45.0}
    assert recalled_camera(record, 240)["horizon"] == 190.0
    above = camera_record(True, -300.0, 45.0, 480)  # a horizon above the image scales too
    assert recalled_camera(above, 960)["horizon"] == -600.0


def test_an_image_without_a_record_has_no_horizon_given():
    assert recalled_camera(None, 3000) == NOT_GIVEN == {"given": False, "horizon": 0.0, "fov": camera_rules.DEFAULT_FOV}
    assert recalled_camera("", 3000) == NOT_GIVEN


@pytest.mark.parametrize(
    "text",
    [
        "not json",
        "[1, 2]",
        '{"format": "another-program", "version": 1, "given": true, "horizon": 1, "fov": 45, "height": 10}',
        '{"format": "ssn-shadow-camera", "version": 2, "given": true, "horizon": 1, "fov": 45, "height": 10}',
        '{"format": "ssn-shadow-camera", "version": 1, "given": 1, "horizon": 1, "fov": 45, "height": 10}',
        '{"format": "ssn-shadow-camera", "version": 1, "given": true, "horizon": NaN, "fov": 45, "height": 10}',
        '{"format": "ssn-shadow-camera", "version": 1, "given": true, "horizon": 1, "fov": "45", "height": 10}',
        '{"format": "ssn-shadow-camera", "version": 1, "given": true, "horizon": 1, "fov": 45, "height": 0}',
        '{"format": "ssn-shadow-camera", "version": 1, "given": true, "horizon": 1, "fov": 45, "height": 10.5}',
        '{"format": "ssn-shadow-camera", "version": 1, "given": true, "horizon": 1, "fov": 45}',
    ],
)
def test_a_record_that_is_none_of_ours_is_no_record(text):
    """Another program's parasite, a newer version's or a damaged one: the image starts as one never shadowed."""
    assert recalled_camera(text, 480) == NOT_GIVEN


def test_a_recalled_camera_stays_inside_the_editors_bounds():
    far = camera_record(True, 90000.0, 150.0, 100)
    lo, hi = camera_rules.EDITOR_HORIZON_RANGE
    assert recalled_camera(far, 1000) == {"given": True, "horizon": hi, "fov": camera_rules.EDITOR_FOV_RANGE[1]}
    assert recalled_camera(camera_record(True, -90000.0, 2.0, 100), 1000)["horizon"] == lo
