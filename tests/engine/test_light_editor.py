"""The host kit's light-map editor (both plug-ins forward their events to it) and its picture."""

import numpy as np
import pytest

from ssn_engine.host_kit import light_map
from ssn_engine.hemisphere import render_light_map
from ssn_engine.host_kit.light_editor import NEW_INTENSITY, NEW_SOFTNESS, STROKE_GAP_S, LightMapEditor
from ssn_engine.host_kit.light_map_picture import map_rgb, overlay_markers


def editor(clock=None):
    changes = []
    lights = light_map.LightMap([light_map.GaussianLight(0.5, 0.5, 0.01, 1.0)])
    ed = LightMapEditor(lights, lambda live, new_stroke: changes.append((live, new_stroke)), clock=clock or (lambda: 0))
    return ed, changes


def test_click_on_empty_sky_adds_and_selects():
    ed, changes = editor()
    ed.press(0.1, 0.2)
    assert len(ed.lights) == 2 and ed.selected == 1
    assert (ed.lights.lights[1].u, ed.lights.lights[1].v) == pytest.approx((0.1, 0.2))
    assert changes == [(False, True)]  # an added light is a complete edit, a new undo step
    ed.drag(0.15, 0.25)
    ed.release()
    assert changes[1:] == [(True, False), (False, False)]  # moving it at once belongs to the same step


def test_drag_moves_keeping_the_grab_offset_and_wraps():
    ed, changes = editor()
    ed.press(0.52, 0.5)  # on the light, a little right of its centre
    assert len(ed.lights) == 1 and ed.selected == 0 and not changes  # a press on a light only grabs it
    ed.drag(0.62, 0.6)
    assert changes == [(True, True)]  # the first move of a drag starts a new undo step
    assert (ed.lights.lights[0].u, ed.lights.lights[0].v) == pytest.approx((0.6, 0.6))
    ed.drag(1.05, 1.5)  # u wraps around the azimuth, v clamps at the horizon
    assert (ed.lights.lights[0].u, ed.lights.lights[0].v) == pytest.approx((0.03, 1.0))
    assert changes[-1] == (True, False)  # live
    ed.release()
    assert changes[-1] == (False, False)  # complete
    n = len(changes)
    ed.release()  # a second release without a drag is not an edit
    assert len(changes) == n


def test_wheel_resizes_and_reweights_within_ranges():
    ed, changes = editor()
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
    assert [c for c in changes if not c[0]] == [(False, True)] + [(False, False)] * 3  # one quick wheel stroke


def test_wheel_targets_the_light_under_the_pointer_and_strokes_by_time():
    now = [0.0]
    lights = light_map.LightMap(
        [light_map.GaussianLight(0.2, 0.5, 0.01, 1), light_map.GaussianLight(0.8, 0.5, 0.01, 1)]
    )
    changes, selections = [], []
    ed = LightMapEditor(lights, lambda *c: changes.append(c), selections.append, clock=lambda: now[0])
    ed.scroll(1, at=(0.8, 0.5))
    assert ed.selected == 1 and selections == [1] and lights.lights[1].softness == pytest.approx(0.0125)
    now[0] += STROKE_GAP_S / 2
    ed.scroll(1, at=(0.5, 0.9))  # empty sky: the selected light
    now[0] += 2 * STROKE_GAP_S
    ed.scroll(-1, at=(0.8, 0.5))
    assert [c[1] for c in changes] == [True, False, True]
    assert lights.lights[0].softness == 0.01


def test_remove():
    ed, changes = editor()
    ed.remove_at(0.0, 0.0)  # nothing there
    assert len(ed.lights) == 1 and not changes
    ed.remove_at(0.5, 0.5)
    assert len(ed.lights) == 0 and changes == [(False, True)]
    ed.press(0.3, 0.3)
    ed.remove_selected()
    assert len(ed.lights) == 0 and ed.selected is None


def test_too_many_lights_is_a_message_not_an_error():
    ed = LightMapEditor(light_map.LightMap([light_map.GaussianLight(i / 50, 0.0, 0.0001, 1) for i in range(50)]))
    ed.press(0.5, 0.9)
    assert len(ed.lights) == 50 and "at most 50" in ed.message and ed.selected is None


def test_controls_and_loading_a_map():
    ed, changes = editor()
    ed.set_intensity(2.5, True)
    ed.set_size(12.0)
    assert (ed.lights.lights[0].angle, ed.lights.lights[0].softness) == (12.0, light_map.angle_softness(12.0))
    assert changes == [(True, True), (False, True)]
    ed.press(0.8, 0.7)
    assert light_map.LightMap.from_json(ed.to_json()) == ed.lights and len(ed.lights) == 2
    ed.load(light_map.preset("overcast"))
    assert len(ed.lights) == 5 and ed.selected == 0 and changes[-1] == (False, True)


def test_a_click_on_empty_sky_adds_a_light_of_the_presets_kind():
    """Not the old 36-degree Gaussian whatever the map: after a preset of disk lights, a disk of its angle (the
    sun's 0.53 degrees); after a preset of Gaussians, a Gaussian; a map with no lights keeps the kind before it."""
    ed = LightMapEditor(light_map.preset("sun"))
    ed.press(0.8, 0.3)
    added = ed.lights.lights[ed.selected]
    assert (added.angle, added.intensity) == (light_map.SUN, NEW_INTENSITY)
    ed.load(light_map.preset("hazy-sun"))
    ed.press(0.8, 0.3)
    assert ed.lights.lights[ed.selected].angle == light_map.HAZY_SUN
    ed.load(light_map.preset("overcast"))
    ed.press(0.1, 0.9)
    added = ed.lights.lights[ed.selected]
    assert (added.angle, added.softness) == (None, NEW_SOFTNESS)
    ed.load(light_map.preset("softbox"))
    ed.load(light_map.LightMap())  # every light removed: still the softbox's kind
    ed.press(0.5, 0.5)
    assert ed.lights.lights[0].angle == light_map.SOFTBOX
    assert LightMapEditor().new_angle == light_map.SOFTBOX  # the default preset's
    assert LightMapEditor(light_map.LightMap()).new_angle == light_map.SOFTBOX


def test_the_intensity_box_sets_the_selected_lights_intensity():
    """An Intensity box (GIMP's dialog): a complete edit, to its two decimals within the range; showing the
    light's own intensity edits nothing; quick steps are one undo step."""
    now = [0.0]
    ed, changes = editor(clock=lambda: now[0])
    ed.enter_intensity(1.0)  # what the box shows of this light: no edit
    assert changes == []
    ed.enter_intensity(2.345)
    assert ed.lights.lights[0].intensity == 2.35 and changes == [(False, True)]
    now[0] += STROKE_GAP_S / 2
    ed.enter_intensity(9.0)
    assert ed.lights.lights[0].intensity == light_map.INTENSITY_RANGE[1] and changes[-1] == (False, False)
    ed.select(None)
    ed.enter_intensity(0.5)
    assert ed.lights.lights[0].intensity == light_map.INTENSITY_RANGE[1] and len(changes) == 2


def test_overlay_draws_rings_and_guides():
    w, h = 64, 32
    rgb = bytearray(3 * w * h)
    overlay_markers(rgb, w, h, light_map.LightMap([light_map.GaussianLight(0.25, 0.5, 0.01, 1)]), 0)
    centre = 3 * (16 * w + 16)
    assert rgb[centre : centre + 3] == bytes((255, 200, 0))  # the selected light's centre cross
    assert rgb[3 * 32 : 3 * 32 + 3] == bytes((110, 110, 130))  # the u = 0.5 guide on row 0


def test_picture_follows_the_lights():
    empty = map_rgb(light_map.LightMap(), 16, 8)
    lit = map_rgb(light_map.LightMap([light_map.GaussianLight(0.5, 0.5, 0.01, 3.0)]), 16, 8)
    assert len(lit) == 16 * 8 * 3 and lit != empty
    centre = (4 * 16 + 8) * 3
    assert lit[centre] > empty[centre]  # bright where the light is
    wrapped = map_rgb(light_map.LightMap([light_map.GaussianLight(0.0, 0.5, 0.01, 3.0)]), 16, 8)
    assert wrapped[(4 * 16) * 3] == wrapped[(4 * 16 + 15) * 3]  # u wraps around


@pytest.mark.parametrize("name", sorted(light_map.PRESETS))
def test_picture_shows_what_the_model_is_given(name):
    """The editor's picture is the engine's light map (hemisphere.render_light_map), tone-mapped."""
    lights = light_map.preset(name)
    picture = np.frombuffer(map_rgb(lights, 64, 32), np.uint8).reshape(32, 64, 3).astype(int)
    elm = render_light_map(lights, 32)
    tone = elm / (1.0 + elm)
    expected = np.rint(255 * (0.10 + (1.0 - 0.10) * np.round(255 * tone) / 255)).astype(int)  # the red channel
    assert np.abs(picture[..., 0] - expected).max() <= 1


def test_the_wheel_resizes_a_disk_light_in_degrees():
    lights = light_map.LightMap([light_map.GaussianLight.disk(0.5, 0.5, 4.0, 1.0)])
    ed = LightMapEditor(lights)
    ed.scroll(1, at=(0.5, 0.5))
    assert lights.lights[0].angle == pytest.approx(5.0)
    ed.scroll(-100)
    assert lights.lights[0].angle == light_map.ANGLE_RANGE[0]
    assert lights.lights[0].softness == light_map.angle_softness(light_map.ANGLE_RANGE[0])
