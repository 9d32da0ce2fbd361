"""The conventions' pinhole camera (ssn_engine.camera)."""

from __future__ import annotations

import numpy as np
import pytest

from ssn_engine.camera import PITCH_RANGE, Camera, camera_for_span, focal_from_fov, fov_from_focal, top_row


@pytest.mark.parametrize("n", [256, 128, 100, 33])
def test_top_row_is_three_percent(n):
    assert top_row(n) == round(0.03 * n)
    assert top_row(256) == 8


@pytest.mark.parametrize("n, pitch, fov", [(256, 15.0, 45.0), (128, 0.0, 35.0), (100, 30.0, 55.0)])
def test_frame_top_puts_the_top_point_on_row_three_percent(n, pitch, fov):
    rng = np.random.default_rng(n)
    points = rng.uniform([-0.3, 0.0, -0.3], [0.3, 0.7, 0.3], (200, 3))
    cam = Camera(n, 0.35, fov=fov, pitch=pitch).frame_top(points)
    rows = cam.project(points)[:, 1]
    assert rows.min() == pytest.approx(top_row(n), abs=1e-9)
    # framing is a pure vertical shift: columns do not move
    plain = Camera(n, 0.35, fov=fov, pitch=pitch)
    assert np.allclose(cam.project(points)[:, 0], plain.project(points)[:, 0])
    assert np.allclose(rows - plain.project(points)[:, 1], cam.shift)


def test_frame_top_is_idempotent():
    points = np.array([[0.0, 0.0, 0.0], [0.0, 0.9, 0.1]])
    cam = Camera(256, 0.45).frame_top(points)
    shift = cam.shift
    assert cam.frame_top(points).shift == pytest.approx(shift)


def test_object_centre_projects_to_the_centre_column():
    cam = Camera(256, 0.5)
    col, _ = cam.project(np.array([0.0, 0.3, 0.0]))
    assert col == pytest.approx(128.0)
    right, _ = cam.project(np.array([0.2, 0.3, 0.0]))
    assert right > 128.0  # +x is the camera's right


@pytest.mark.parametrize("pitch", [0.0, 15.0, 30.0])
def test_ground_points_lie_on_the_ground_and_pixels_above_the_horizon_are_invalid(pitch):
    n = 64
    cam = Camera(n, 0.5, pitch=pitch)
    cam.frame_top(np.array([[0.0, 1.0, 0.0]]))
    points, valid = cam.ground_points()
    assert points.shape == (n, n, 3) and valid.shape == (n, n)
    assert np.allclose(points[valid][:, 1], 0.0, atol=1e-9)
    # ground points project back into their own pixel centres
    image = cam.project(points[valid])
    rows, cols = np.nonzero(valid)
    assert np.allclose(image[:, 0], cols + 0.5, atol=1e-6)
    assert np.allclose(image[:, 1], rows + 0.5, atol=1e-6)
    # validity is per row: everything below the horizon row, nothing above it
    horizon = 0.5 * n - cam.focal * np.tan(np.radians(pitch)) + cam.shift  # where a level ray lands
    centres = np.arange(n) + 0.5
    assert np.array_equal(valid.all(axis=1), centres > horizon + 1e-6)
    assert not valid[centres < horizon - 1e-6].any()
    # rays through valid pixels point down, rays through invalid ones do not
    rays = cam.pixel_rays()
    assert np.all(rays[valid][:, 1] < 0) and np.all(rays[~valid][:, 1] >= -1e-9)


def test_pitch_zero_has_the_horizon_at_the_camera_height():
    cam = Camera(64, 0.5, pitch=0.0)
    _, valid = cam.ground_points()
    assert not valid[:32].any() and valid[32:].all()


def test_to_world_maps_the_elm_basis():
    cam = Camera(32, 0.5)
    basis = np.eye(3)  # right, up, forward
    world = cam.to_world(basis)
    assert np.allclose(world, [[1, 0, 0], [0, 1, 0], [0, 0, -1]])


@pytest.mark.parametrize("horizon", [-60.0, 0.0, 20.0, 50.0])
@pytest.mark.parametrize("fov", [35.0, 55.0])
def test_camera_for_span_puts_the_horizon_on_the_given_row(horizon, fov):
    n, top, base = 128, 4.0, 70.0
    cam, height = camera_for_span(n, top, base, horizon, focal_from_fov(n, fov))
    assert cam.horizon == pytest.approx(horizon, abs=0.05)
    assert cam.fov == pytest.approx(fov)
    # the card it fits stands on the base row and reaches the top row
    assert cam.project(np.array([0.0, 0.0, 0.0]))[1] == pytest.approx(base, abs=1e-6)
    assert cam.project(np.array([0.0, height, 0.0]))[1] == pytest.approx(top, abs=0.05)


def test_a_higher_horizon_means_a_camera_looking_further_down():
    pitches = [camera_for_span(128, 4.0, 70.0, h, 150.0)[0].pitch for h in (50.0, 10.0, -40.0)]
    assert pitches[0] < pitches[1] < pitches[2]


def test_camera_for_span_without_input_is_the_default_camera():
    cam, _ = camera_for_span(128, 4.0, 70.0)
    assert cam.pitch == 15.0 and cam.fov == 45.0


def test_an_unreachable_horizon_gets_the_nearest_pitch():
    """A horizon below the card's foot would put the camera under the ground: the lowest pitch is used."""
    cam, _ = camera_for_span(128, 4.0, 70.0, 500.0, 150.0)
    assert cam.pitch == pytest.approx(PITCH_RANGE[0], abs=1e-4)


def test_a_wide_lens_looking_steeply_down_gets_the_steepest_card_it_can_fit():
    """A horizon far above a cutout seen through a 100 degree lens: the steep pitches that would frame it put the
    card's top behind the camera; the camera is the steepest one that still frames the card, not a crash."""
    n, top, base = 128, 4.0, 70.0
    cam, height = camera_for_span(n, top, base, -200.0, focal_from_fov(n, 100.0))
    assert 0.0 < cam.pitch < PITCH_RANGE[1] and np.isfinite(height) and height > 0
    assert cam.project(np.array([0.0, 0.0, 0.0]))[1] == pytest.approx(base, abs=1e-6)
    assert cam.project(np.array([0.0, height, 0.0]))[1] == pytest.approx(top, abs=0.01 * (base - top))


def test_focal_length_and_field_of_view_are_inverse():
    assert fov_from_focal(256, focal_from_fov(256, 45.0)) == pytest.approx(45.0)
    assert focal_from_fov(256, 90.0) == pytest.approx(128.0)


def test_a_point_along_a_ray_projects_back_to_its_image_point_at_its_depth():
    """``rays`` and ``projection`` are each other's inverse: the point at camera depth t along the ray through
    (col, row) lands on (col, row), and the projection's third row is that depth."""
    cam = Camera(128, 0.4, fov=50.0, pitch=25.0)
    cam.shift = 7.0
    cols, rows, t = np.array([3.5, 64.0, 120.25]), np.array([10.0, 70.5, 127.0]), np.array([1.5, 2.0, 3.25])
    points = cam.centre + t[:, None] * cam.rays(cols, rows)
    image = np.concatenate([points, np.ones((3, 1))], axis=1) @ cam.projection().T
    assert np.allclose(image[:, 2], t) and np.allclose(image[:, :2] / image[:, 2:], np.stack([cols, rows], 1))
    assert np.allclose(np.stack(cam.project_xyz(*points.T), 1), np.stack([cols, rows], 1))
