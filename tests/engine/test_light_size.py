"""A light's size in degrees as both editors show and edit it (host kit: light_size, the editor's Size box and
wheel, the map's markers and labels)."""

import math

import pytest

from ssn_engine.host_kit import light_map, light_size
from ssn_engine.host_kit.light_editor import STROKE_GAP_S, LightMapEditor
from ssn_engine.host_kit.light_map_picture import GLYPHS, MIN_MARKER, marker, overlay_markers, text_width


def disk_editor(angle=3.0, clock=None):
    changes = []
    lights = light_map.LightMap([light_map.GaussianLight.disk(0.35, 0.6, angle, 2.0)])
    ed = LightMapEditor(lights, lambda live, new: changes.append((live, new)), clock=clock or (lambda: 0.0))
    return ed, changes


def test_the_size_box_shows_the_suns_size_exactly_and_steps_by_the_values_decade():
    assert light_size.SIZE_RANGE == light_map.ANGLE_RANGE == (0.1, 40.0)
    assert light_size.clamp_size(0.53) == 0.53 and light_size.clamp_size(0.534) == 0.53
    assert light_size.clamp_size(0.0) == 0.1 and light_size.clamp_size(90) == 40.0
    assert light_size.increments(0.53) == (0.01, pytest.approx(0.1))
    assert light_size.increments(3.0) == (pytest.approx(0.1), 1.0)
    assert light_size.increments(16.0) == (1.0, 10.0)
    assert light_size.increments(1.0) == (pytest.approx(0.1), 1.0)
    assert light_size.increments(0.1) == (0.01, pytest.approx(0.1))


def test_setting_the_size_makes_a_disk_of_that_angle_keeping_its_power():
    ed, changes = disk_editor(12.0)
    power = ed.lights.lights[0].power
    ed.set_size(0.53)
    light = ed.lights.lights[0]
    assert (light.u, light.v, light.angle, light.intensity) == (0.35, 0.6, 0.53, 2.0)
    assert light.power == power
    assert light_map.LightMap.from_json(ed.to_json()).lights[0].angle == 0.53  # what the file carries
    assert changes == [(False, True)]
    ed.set_size(0.53)  # the box showing the light's size edits nothing
    assert changes == [(False, True)]
    ed.set_size(123.0)
    assert ed.lights.lights[0].angle == 40.0


def test_a_gaussian_light_given_a_size_becomes_a_disk_of_the_same_power():
    for softness, intensity in ((0.002, 2.5), (0.01, 1.0), (0.05, 0.5)):
        lights = light_map.LightMap([light_map.GaussianLight(0.4, 0.5, softness, intensity)])
        before = lights.lights[0].power
        LightMapEditor(lights).set_size(3.0)
        light = lights.lights[0]
        assert light.angle == 3.0
        assert light.power == pytest.approx(before, rel=1e-9)
    # as far as the intensity's range allows
    lights = light_map.LightMap([light_map.GaussianLight(0.4, 0.5, 0.1, 2.5)])
    LightMapEditor(lights).set_size(3.0)
    assert lights.lights[0].intensity == light_map.INTENSITY_RANGE[1]


def test_size_steps_in_quick_succession_are_one_undo_step():
    now = [0.0]
    ed, changes = disk_editor(3.0, clock=lambda: now[0])
    ed.set_size(3.1)
    now[0] += 0.1
    ed.set_size(3.2)
    now[0] += STROKE_GAP_S + 0.1
    ed.set_size(3.3)
    assert changes == [(False, True), (False, False), (False, True)]


def test_nothing_selected_sets_no_size():
    ed, changes = disk_editor()
    ed.select(None)
    ed.set_size(1.0)
    assert ed.lights.lights[0].angle == 3.0 and changes == []


def test_the_wheel_steps_a_disk_to_sizes_the_box_can_show():
    ed, _ = disk_editor(0.53)
    ed.scroll(1)
    assert ed.lights.lights[0].angle == 0.66  # 0.53 * 1.25 = 0.6625, shown to two decimals
    assert light_size.shown_size(ed.lights.lights[0]) == 0.66
    ed.scroll(-1)
    assert ed.lights.lights[0].angle == 0.53


def test_labels_say_the_size_in_degrees():
    assert light_size.size_text(light_map.GaussianLight.disk(0.5, 0.5, 0.53)) == "0.53\N{DEGREE SIGN}"
    assert light_size.size_text(light_map.GaussianLight.disk(0.5, 0.5, 16.0)) == "16\N{DEGREE SIGN}"
    assert light_size.size_text(light_map.GaussianLight.disk(0.5, 0.5, 31.25)) == "31.25\N{DEGREE SIGN}"
    gaussian = light_map.GaussianLight(0.5, 0.5, 0.004, 1.0)  # no edge: about the disk as wide
    assert light_size.size_text(gaussian) == "\N{ALMOST EQUAL TO}23\N{DEGREE SIGN}"
    assert light_size.shown_size(gaussian) == pytest.approx(22.77, abs=0.01)
    assert light_size.shown_size(light_map.GaussianLight(0.5, 0.5, 0.1, 1.0)) == 40.0  # wider than the box goes
    assert all(c in GLYPHS for c in "0123456789.\N{DEGREE SIGN}\N{ALMOST EQUAL TO}")


def _extent(m):
    points = [p for line in m.outline for p in line]
    xs, ys = [x for x, _ in points], [y for _, y in points]
    return max(xs) - min(xs), max(ys) - min(ys)


def test_the_map_draws_a_disk_at_its_true_size():
    width, height = 384, 192  # GIMP's map: 90 degrees of elevation in 192 px
    softbox = marker(light_map.GaussianLight.disk(0.5, 0.5, 16.0), width, height)
    across, down = _extent(softbox)
    assert softbox.true_size and softbox.label == "16\N{DEGREE SIGN}"
    assert down == pytest.approx(16.0 / 90.0 * height, rel=0.02)  # 16 degrees of elevation
    # 45 degrees up, 16 degrees of arc span 16 / cos(45) degrees of azimuth: wider across than down
    assert across == pytest.approx(16.0 / math.cos(math.radians(45)) / 360.0 * width, rel=0.03)
    sun = marker(light_map.GaussianLight.disk(0.5, 0.5, 0.53), width, height)
    assert not sun.true_size and sun.label == "0.53\N{DEGREE SIGN}"
    assert _extent(sun)[1] == pytest.approx(2 * MIN_MARKER, rel=0.01)  # smaller than a marker: the marker
    low = marker(light_map.GaussianLight.disk(0.5, 0.95, 16.0), width, height)  # cut by the horizon
    assert max(y for line in low.outline for _, y in line) > height


def test_a_disk_over_the_seam_or_the_zenith_is_drawn_in_pieces_that_wrap():
    seam = marker(light_map.GaussianLight.disk(0.0, 0.5, 20.0), 384, 192)
    xs = [x for line in seam.outline for x, _ in line]
    assert min(xs) < 0 < max(xs) and len(seam.outline) == 1  # one ring running off the left edge
    top = marker(light_map.GaussianLight.disk(0.5, 0.02, 20.0), 384, 192)
    assert all(abs(b[0] - a[0]) <= 384 / 4 for line in top.outline for a, b in zip(line, line[1:], strict=False))


def _pixels(rgb, width, colour):
    return {(i // 3 % width, i // 3 // width) for i in range(0, len(rgb), 3) if tuple(rgb[i : i + 3]) == colour}


def test_gimps_overlay_draws_the_sun_and_a_softbox_differently_with_their_labels():
    width, height = 384, 192
    drawn = {}
    for angle in (0.53, 16.0):
        rgb = bytearray(3 * width * height)
        overlay_markers(rgb, width, height, light_map.LightMap([light_map.GaussianLight.disk(0.5, 0.5, angle)]), 0)
        drawn[angle] = _pixels(rgb, width, (255, 200, 0))
    sun, softbox = drawn[0.53], drawn[16.0]
    left_of = [x for x, y in softbox if y == 96 and x < 192 - 5]  # the rim on the centre's row, left of it
    assert left_of and 192 - max(left_of) == pytest.approx(16 / math.cos(math.radians(45)) / 360 * width / 2, abs=2)
    assert not [x for x, y in sun if y == 96 and x < 192 - 6]  # the sun's ring is the small marker
    # each is labelled right of its marker, in the pixel font
    for angle, pixels in drawn.items():
        m = marker(light_map.GaussianLight.disk(0.5, 0.5, angle), width, height)
        x0 = round(m.label_x)
        label = {(x, y) for x, y in pixels if x0 <= x < x0 + text_width(m.label) and 86 <= y <= 106}
        assert len(label) > 30, angle


def test_a_label_at_the_right_edge_goes_left_of_its_marker():
    width, height = 384, 192
    rgb = bytearray(3 * width * height)
    light = light_map.GaussianLight.disk(0.99, 0.5, 3.0)
    overlay_markers(rgb, width, height, light_map.LightMap([light]), 0)
    m = marker(light, width, height)
    right = round(m.label_x_left)
    label = {(x, y) for x, y in _pixels(rgb, width, (255, 200, 0)) if right - text_width(m.label) <= x < right - 1}
    assert label
