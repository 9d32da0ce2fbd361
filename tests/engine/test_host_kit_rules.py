"""The rules the host kit defines once for every front end: camera bounds and notes, the sky map, the AO edits."""

from __future__ import annotations

import numpy as np
import pytest

from ssn_engine.framing import frame_alpha
from ssn_engine.hemisphere import render_light_map, render_light_maps
from ssn_engine.host_kit import camera_rules
from ssn_engine.host_kit.ao_edits import AoEdits, strength_edits
from ssn_engine.host_kit.defaults import MAX_AO_STRENGTH
from ssn_engine.host_kit.light_map import GaussianLight, LightMap, preset
from ssn_engine.host_kit.sky_map import NETWORK_SHAPE, check_elm_shape, map_values


def test_the_editors_offer_a_range_inside_the_engine_s():
    lo, hi = camera_rules.FOV_RANGE
    e_lo, e_hi = camera_rules.EDITOR_FOV_RANGE
    assert lo < e_lo <= camera_rules.DEFAULT_FOV <= e_hi < hi


@pytest.mark.parametrize("fov", [0.5, 171.0, float("nan"), True, "45"])
def test_the_engine_refuses_a_field_of_view_outside_its_range(fov):
    with pytest.raises(ValueError, match="camera.fov: expected 1 to 170 degrees"):
        camera_rules.check_fov(fov, "camera.fov")
    _, framing = frame_alpha(np.pad(np.ones((20, 10), np.float32), 40), 256)
    if isinstance(fov, float):
        with pytest.raises(ValueError, match="field of view"):
            framing.camera_input(10.0, fov)


def test_a_camera_read_becomes_the_editors_settings_and_note():
    """Whole rows and degrees within the editors' bounds; the note says where the preview draws the horizon."""
    settings = camera_rules.camera_read_settings
    assert settings({"horizon": 80.6, "fov": 47.4}) == {"horizon": 81.0, "fov": 47.0}
    assert settings({"horizon": -9e6, "fov": 150.0}) == {"horizon": -100000.0, "fov": 120.0}
    assert settings({"horizon": 9e6, "fov": 3.0}) == {"horizon": 100000.0, "fov": 10.0}
    note = camera_rules.camera_read_note
    assert "horizon at row 81 (dotted blue), 47° field of view" in note({"horizon": 80.6, "fov": 47.4}, 300)
    assert "(above the image)" in note({"horizon": -0.6, "fov": 47.0}, 300)
    assert "(below the image)" in note({"horizon": 300.0, "fov": 47.0}, 300)
    assert camera_rules.scaled_camera({"horizon": 300.0, "fov": 50.0}, 0.25) == {"horizon": 75.0, "fov": 50.0}


def test_a_preview_fits_its_box_and_a_click_on_it_names_a_canvas_row():
    """A portrait image's preview is as tall as a landscape one's, not taller (the dialog fits the screen); a
    click on the preview's row ``y`` names the canvas row it shows."""
    size = camera_rules.preview_size
    assert size(640, 480, 384, 288) == (384, 288, 0.6)
    assert size(480, 640, 384, 288) == (216, 288, 0.45)
    assert size(1000, 100, 384, 288) == (384, 38, 0.384)
    assert size(200, 150, 384, 288) == (200, 150, 1.0)
    assert size(480, 640, 384) == (288, 384, 0.6)  # no height limit: the longer side only
    assert camera_rules.row_from_preview(100, 0.6) == 167.0
    assert camera_rules.row_from_preview(0, 0.45) == 0.0
    assert camera_rules.row_from_preview(50, 1e-6) == camera_rules.EDITOR_HORIZON_RANGE[1]


def test_the_horizon_from_guides_is_the_first_horizontal_guide():
    assert camera_rules.horizon_from_guides([300.4, 120.0]) == 300.0
    assert camera_rules.horizon_from_guides([]) is None
    assert "horizontal guide" in camera_rules.NO_GUIDE and "From guide" in camera_rules.NO_GUIDE


def test_the_stdlib_sky_map_is_the_engine_s():
    """The kit's definition (what the editors draw) and the engine's numpy form give the same ELM, a light at the
    azimuth's seam and a light far smaller than a texel included."""
    rng = np.random.default_rng(3)
    maps = [preset(name) for name in ("softbox", "two-lights", "low-sun-left", "high-sun")]
    maps.append(LightMap([GaussianLight(0.0, 0.9, 0.0005, 2.0), GaussianLight(0.99, 0.1, 0.03, 0.5)]))
    maps.append(LightMap([GaussianLight(*rng.random(2), 0.001 + 0.05 * rng.random(), 3.0) for _ in range(3)]))
    for lights in maps:
        for h in (NETWORK_SHAPE[0], 5):
            exact = np.array(map_values(lights, 2 * h, h), np.float64)
            assert np.allclose(render_light_map(lights, h), exact, rtol=1e-5, atol=1e-7)
    assert render_light_map(LightMap()).shape == NETWORK_SHAPE and not render_light_map(LightMap()).any()
    u, v = np.array([[0.2, 0.7]]), np.array([[0.3, 0.5]])
    both = render_light_maps(u, v, np.full((1, 2), 0.01), np.array([[1.0, 0.0]]))[0]
    alone = render_light_map(LightMap([GaussianLight(0.2, 0.3, 0.01, 1.0)]))
    assert np.allclose(both, alone)  # intensity 0: no light


def test_the_elm_shape_is_checked_once():
    check_elm_shape((3, 16, 32), 3)
    for shape in ((3, 16, 31), (2, 16, 32), (16, 32)):
        with pytest.raises(ValueError, match=r"elms: expected shape \(3, 16, 32\)"):
            check_elm_shape(shape, 3)


def test_the_ao_strength_op_is_last_and_absent_at_one():
    assert strength_edits(1.0) == [] and strength_edits(0) == [{"op": "strength", "value": 0.0}]
    edits = AoEdits()
    edits.grow(3)
    assert edits.to_list(2.5) == [{"op": "grow", "pixels": 3}, {"op": "strength", "value": 2.5}]
    assert edits.to_list() == [{"op": "grow", "pixels": 3}]
    with pytest.raises(ValueError, match="AO strength"):
        edits.to_list(MAX_AO_STRENGTH + 0.5)
    with pytest.raises(ValueError, match="AO strength"):
        strength_edits(-0.1)
