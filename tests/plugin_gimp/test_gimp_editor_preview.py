"""The light-map editor's gestures and the preview compositing, without GTK."""

import pytest
from ssn_editor import LightMapEditor, overlay_markers
from ssn_preview import multiply_composite, preview_size

from ssn_engine import light_map


def editor():
    changes = []
    ed = LightMapEditor(light_map.LightMap([light_map.GaussianLight(0.5, 0.5, 0.01, 1.0)]), changes.append)
    return ed, changes


def test_click_on_empty_sky_adds_and_selects():
    ed, changes = editor()
    ed.press(0.1, 0.2)
    assert len(ed.lights) == 2 and ed.selected == 1
    assert (ed.lights.lights[1].u, ed.lights.lights[1].v) == pytest.approx((0.1, 0.2))
    assert changes[0] is True  # an added light is a complete edit


def test_drag_moves_keeping_the_grab_offset_and_wraps():
    ed, changes = editor()
    ed.press(0.52, 0.5)  # on the light, a little right of its centre
    assert len(ed.lights) == 1 and ed.selected == 0
    ed.drag(0.62, 0.6)
    assert (ed.lights.lights[0].u, ed.lights.lights[0].v) == pytest.approx((0.6, 0.6))
    ed.drag(1.05, 1.5)  # u wraps around the azimuth, v clamps at the horizon
    assert (ed.lights.lights[0].u, ed.lights.lights[0].v) == pytest.approx((0.03, 1.0))
    assert changes[-1] is False
    ed.release()
    assert changes[-1] is True
    n = len(changes)
    ed.release()  # a second release without a drag is not an edit
    assert len(changes) == n


def test_wheel_resizes_and_reweights_within_ranges():
    ed, _ = editor()
    ed.press(0.5, 0.5)
    ed.release()
    ed.scroll(1)
    assert ed.lights.lights[0].softness == pytest.approx(0.0125)
    ed.scroll(100)
    assert ed.lights.lights[0].softness == light_map.SOFTNESS_RANGE[1]
    ed.scroll(3, intensity=True)
    assert ed.lights.lights[0].intensity == pytest.approx(1.3)
    ed.scroll(-100, intensity=True)
    assert ed.lights.lights[0].intensity == 0.0


def test_remove():
    ed, changes = editor()
    ed.remove_at(0.0, 0.0)  # nothing there
    assert len(ed.lights) == 1 and not changes
    ed.remove_at(0.5, 0.5)
    assert len(ed.lights) == 0 and changes == [True]
    ed.press(0.3, 0.3)
    ed.remove_selected()
    assert len(ed.lights) == 0 and ed.selected is None


def test_too_many_lights_is_a_message_not_an_error():
    ed = LightMapEditor(light_map.LightMap([light_map.GaussianLight(i / 50, 0.0, 0.0001, 1) for i in range(50)]))
    ed.press(0.5, 0.9)
    assert len(ed.lights) == 50 and "at most 50" in ed.message and ed.selected is None


def test_json_is_a_valid_light_map_argument():
    import ssn_settings

    ed, _ = editor()
    ed.press(0.8, 0.7)
    params = ssn_settings.resolve_light_map(ed.to_json())
    assert len(params["light_map"]["lights"]) == 2
    ed.load(light_map.preset("overcast"))
    assert len(ed.lights) == 5 and ed.selected is None


def test_overlay_draws_rings_and_guides():
    w, h = 64, 32
    rgb = bytearray(3 * w * h)
    overlay_markers(rgb, w, h, light_map.LightMap([light_map.GaussianLight(0.25, 0.5, 0.01, 1)]), 0)
    centre = 3 * (16 * w + 16)
    assert rgb[centre : centre + 3] == bytes((255, 200, 0))  # the selected light's centre cross
    assert rgb[3 * 32 : 3 * 32 + 3] == bytes((110, 110, 130))  # the u = 0.5 guide on row 0


def test_preview_size():
    assert preview_size(1024, 512) == (384, 192, 0.375)
    assert preview_size(100, 50) == (100, 50, 1.0)


def test_multiply_composite():
    # 2 x 1 RGBA background (rowstride 8), layer 1 x 1 at x = 1: colour (0, 255, 0), alpha 255
    bg = bytes([200, 200, 200, 255, 100, 100, 100, 255])
    out = multiply_composite(bg, 2, 1, 8, 4, bytes([0, 255, 0, 255]), 1, 0, 1, 1)
    assert out == bytes([200, 200, 200, 0, 100, 0])
    half = multiply_composite(bg, 2, 1, 8, 4, bytes([0, 0, 0, 128]), 0, 0, 1, 1)
    assert half[:3] == bytes([100, 100, 100]) and half[3:] == bytes([100, 100, 100])
    # the cutout above the shadow layer hides it: fully where opaque, half where half transparent
    cover = multiply_composite(bg, 2, 1, 8, 4, bytes([0, 0, 0, 255]) * 2, 0, 0, 2, 1, bytes([255, 128]))
    assert cover[:3] == bytes([200, 200, 200]) and cover[3:] == bytes([50, 50, 50])
    # a layer hanging off the image is clipped
    assert multiply_composite(bg, 2, 1, 8, 4, bytes([0, 0, 0, 255]) * 4, 1, -1, 2, 2)[3:] == bytes(3)


def test_draw_horizon():
    from ssn_preview import HORIZON_RGB, draw_horizon

    rgb = bytes(3 * 20 * 10)
    out = draw_horizon(rgb, 20, 10, 4.6)
    assert out[3 * (4 * 20) : 3 * (4 * 20) + 3] == HORIZON_RGB  # row 4, first dash
    assert out[3 * (4 * 20 + 6) : 3 * (4 * 20 + 6) + 3] == bytes(3)  # a gap
    assert sum(out[: 3 * 4 * 20]) == 0 and sum(out[3 * 5 * 20 :]) == 0  # only that row
    assert draw_horizon(rgb, 20, 10, -3.0) == rgb and draw_horizon(rgb, 20, 10, 10.0) == rgb
