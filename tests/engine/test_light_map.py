"""The light-map editor model (ssn_engine.host_kit.light_map): editing, hit testing, JSON, presets."""

from __future__ import annotations

import json
import math
import random
import subprocess
import sys

import pytest

from ssn_engine.host_kit import light_map as lm_mod
from ssn_engine.host_kit.light_map import (
    DEFAULT_PRESET,
    MAX_LIGHTS,
    PRESETS,
    GaussianLight,
    LightMap,
    LightMapError,
    softness_angle,
    preset,
)


def test_add_returns_index_and_keeps_values():
    lm = LightMap()
    assert lm.add(0.2, 0.3, 0.01, 1.5) == 0
    assert lm.add(0.7, 0.6) == 1
    assert len(lm) == 2
    first = lm.lights[0]
    assert (first.u, first.v, first.softness, first.intensity) == (0.2, 0.3, 0.01, 1.5)


def test_add_wraps_u_and_clamps_the_rest():
    lm = LightMap()
    lm.add(1.25, 1.7, softness=5.0, intensity=9.0)
    lm.add(-0.25, -0.3, softness=0.0, intensity=-1.0)
    a, b = lm.lights
    assert a.u == pytest.approx(0.25) and a.v == 1.0
    assert a.softness == lm_mod.SOFTNESS_RANGE[1] and a.intensity == lm_mod.INTENSITY_RANGE[1]
    assert b.u == pytest.approx(0.75) and b.v == 0.0
    assert b.softness == lm_mod.SOFTNESS_RANGE[0] and b.intensity == 0.0


def test_add_refuses_more_than_max_lights():
    lm = LightMap()
    for i in range(MAX_LIGHTS):
        lm.add(i / MAX_LIGHTS, 0.5)
    with pytest.raises(LightMapError, match="lights"):
        lm.add(0.5, 0.5)
    assert len(lm) == MAX_LIGHTS


@pytest.mark.parametrize(
    "u, v, expected_u, expected_v",
    [
        (1.1, 0.5, 0.1, 0.5),  # past the right edge: wraps to the left
        (-0.1, 0.5, 0.9, 0.5),  # past the left edge: wraps to the right
        (2.3, 0.5, 0.3, 0.5),
        (0.4, -0.2, 0.4, 0.0),  # above the zenith: clamped
        (0.4, 1.4, 0.4, 1.0),  # below the horizon: clamped
    ],
)
def test_move_wraps_u_and_clamps_v(u, v, expected_u, expected_v):
    lm = LightMap()
    lm.add(0.5, 0.5, 0.02, 2.0)
    lm.move(0, u, v)
    light = lm.lights[0]
    assert light.u == pytest.approx(expected_u)
    assert light.v == pytest.approx(expected_v)
    assert 0.0 <= light.u <= 1.0
    # moving keeps the light's softness and intensity
    assert (light.softness, light.intensity) == (0.02, 2.0)


def test_resize_and_reweight_clamp_to_table_1():
    lm = LightMap()
    lm.add(0.5, 0.5, 0.01, 1.0)
    lm.resize(0, 0.05)
    lm.reweight(0, 2.5)
    assert (lm.lights[0].softness, lm.lights[0].intensity) == (0.05, 2.5)
    lm.resize(0, 10.0)
    lm.reweight(0, 10.0)
    assert (lm.lights[0].softness, lm.lights[0].intensity) == (0.1, 3.0)
    lm.resize(0, -1.0)
    lm.reweight(0, -1.0)
    assert (lm.lights[0].softness, lm.lights[0].intensity) == (1e-4, 0.0)
    assert (lm.lights[0].u, lm.lights[0].v) == (0.5, 0.5)


def test_delete_removes_only_that_light():
    lm = LightMap()
    for u in (0.1, 0.2, 0.3):
        lm.add(u, 0.5)
    lm.delete(1)
    assert [light.u for light in lm] == [0.1, 0.3]


@pytest.mark.parametrize("bad", [math.nan, math.inf, -math.inf])
def test_edits_reject_non_finite_values(bad):
    lm = LightMap()
    lm.add(0.5, 0.5)
    for edit in (
        lambda: lm.add(bad, 0.5),
        lambda: lm.add(0.5, bad),
        lambda: lm.move(0, bad, 0.5),
        lambda: lm.move(0, 0.5, bad),
        lambda: lm.resize(0, bad),
        lambda: lm.reweight(0, bad),
    ):
        with pytest.raises(LightMapError):
            edit()
    assert len(lm) == 1 and lm.lights[0] == GaussianLight(0.5, 0.5)


@pytest.mark.parametrize(
    "field, kwargs",
    [
        ("u", dict(u=-0.1, v=0.5)),
        ("u", dict(u=1.5, v=0.5)),
        ("v", dict(u=0.5, v=-0.01)),
        ("softness", dict(u=0.5, v=0.5, softness=-0.01)),
        ("softness", dict(u=0.5, v=0.5, softness=0.5)),
        ("intensity", dict(u=0.5, v=0.5, intensity=-1.0)),
        ("intensity", dict(u=0.5, v=0.5, intensity=math.nan)),
        ("u", dict(u=math.nan, v=0.5)),
        ("v", dict(u=0.5, v="0.5")),
        ("u", dict(u=True, v=0.5)),
    ],
)
def test_gaussian_light_rejects_bad_values_naming_the_field(field, kwargs):
    with pytest.raises(LightMapError, match=rf"^{field}:"):
        GaussianLight(**kwargs)


def test_hit_test_finds_nearest_light():
    lm = LightMap()
    lm.add(0.30, 0.5, 1e-4)
    lm.add(0.34, 0.5, 1e-4)
    assert lm.hit_test(0.305, 0.5) == 0
    assert lm.hit_test(0.335, 0.5) == 1
    assert lm.hit_test(0.30, 0.5) == 0


def test_hit_test_misses_far_away_and_respects_tolerance():
    lm = LightMap()
    lm.add(0.5, 0.5, 1e-4)  # radius 0.01 map heights
    # 0.05 in u is 0.1 map heights on the 2:1 map
    assert lm.hit_test(0.55, 0.5) is None
    assert lm.hit_test(0.55, 0.5, tolerance=0.11) == 0
    assert lm.hit_test(0.5, 0.55, tolerance=0.06) == 0
    assert lm.hit_test(0.5, 0.57, tolerance=0.06) is None
    assert LightMap().hit_test(0.5, 0.5) is None


def test_hit_test_large_light_is_hit_within_its_radius():
    lm = LightMap()
    lm.add(0.5, 0.5, 0.09)  # radius 0.3 map heights
    assert lm.hit_test(0.5, 0.75, tolerance=0.01) == 0
    assert lm.hit_test(0.5, 0.85, tolerance=0.01) is None


@pytest.mark.parametrize("light_u, click_u", [(0.99, 0.01), (0.01, 0.99), (0.0, 1.0), (1.0, 0.0)])
def test_hit_test_wraps_across_u_0_and_1(light_u, click_u):
    lm = LightMap()
    lm.add(0.5, 0.5)
    lm.lights.append(GaussianLight(light_u, 0.4, 1e-4))
    assert lm.hit_test(click_u, 0.4) == 1


def test_json_round_trip():
    lm = LightMap()
    lm.add(0.123456789, 0.987654321, 0.0123, 2.75)
    lm.add(0.0, 1.0, 1e-4, 0.0)
    text = lm.to_json()
    data = json.loads(text)
    assert data["format"] == "ssn-shadow-elm" and data["version"] == 1
    assert LightMap.from_json(text).lights == lm.lights
    assert LightMap.from_dict(lm.to_dict()).lights == lm.lights


def test_copy_is_independent():
    lm = LightMap()
    lm.add(0.5, 0.5)
    other = lm.copy()
    other.move(0, 0.1, 0.1)
    other.add(0.2, 0.2)
    assert len(lm) == 1 and lm.lights[0].u == 0.5


def _doc(lights):
    return {"format": "ssn-shadow-elm", "version": 1, "lights": lights}


GOOD = {"u": 0.5, "v": 0.5, "softness": 0.01, "intensity": 1.0}


@pytest.mark.parametrize(
    "data, pattern",
    [
        (_doc([GOOD, GOOD, dict(GOOD, u=1.5)]), r"^lights\[2\]\.u: .*1\.5"),
        (_doc([dict(GOOD, v=-1)]), r"^lights\[0\]\.v:"),
        (_doc([GOOD, dict(GOOD, softness=0.0)]), r"^lights\[1\]\.softness:"),
        (_doc([dict(GOOD, intensity=-0.5)]), r"^lights\[0\]\.intensity:"),
        (_doc([dict(GOOD, intensity="2")]), r"^lights\[0\]\.intensity:"),
        (_doc([GOOD, {"u": 0.5, "v": 0.5, "softness": 0.01}]), r"^lights\[1\]\.intensity: missing"),
        (_doc([GOOD, 3]), r"^lights\[1\]: expected an object"),
        (_doc("nope"), r"^lights: expected a list"),
        (_doc([GOOD] * (MAX_LIGHTS + 1)), r"^lights: at most"),
        ({"version": 1, "lights": []}, r"^format:"),
        ({"format": "something-else", "version": 1, "lights": []}, r"^format:"),
        ({"format": "ssn-shadow-elm", "version": 2, "lights": []}, r"^version:.*2"),
        ({"format": "ssn-shadow-elm", "lights": []}, r"^version:"),
        ([1, 2], r"light map: expected a JSON object"),
    ],
)
def test_malformed_json_errors_name_the_field(data, pattern):
    with pytest.raises(LightMapError, match=pattern):
        LightMap.from_dict(data)
    with pytest.raises(LightMapError, match=pattern):
        LightMap.from_json(json.dumps(data))


@pytest.mark.parametrize("text", ["", "{", "not json", '{"format": "ssn-shadow-elm", "version": 1, "lights": [NaN'])
def test_invalid_json_text(text):
    with pytest.raises(LightMapError, match="light map: not valid JSON"):
        LightMap.from_json(text)


@pytest.mark.parametrize("value", ["NaN", "Infinity", "-Infinity"])
def test_non_finite_json_numbers_rejected(value):
    light = f'{{"u": 0.5, "v": 0.5, "softness": 0.01, "intensity": {value}}}'
    text = f'{{"format": "ssn-shadow-elm", "version": 1, "lights": [{light}]}}'
    with pytest.raises(LightMapError, match=r"lights\[0\]\.intensity"):
        LightMap.from_json(text)


@pytest.mark.parametrize("name", list(PRESETS))
def test_every_preset_loads_and_round_trips(name):
    lm = preset(name)
    assert 1 <= len(lm) <= MAX_LIGHTS
    assert LightMap.from_json(lm.to_json()).lights == lm.lights
    # presets are fresh objects: editing one does not change the next
    lm.delete(0)
    assert len(preset(name)) == len(lm) + 1


def test_default_preset_exists():
    assert DEFAULT_PRESET in PRESETS


def test_unknown_preset_names_it_and_lists_choices():
    with pytest.raises(LightMapError) as info:
        preset("sunset-glow")
    message = str(info.value)
    assert "sunset-glow" in message
    for name in PRESETS:
        assert name in message


def test_random_within_table_1_ranges():
    rng = random.Random(1234)
    counts = set()
    for _ in range(200):
        lm = LightMap.random(rng)
        counts.add(len(lm))
        assert 1 <= len(lm) <= MAX_LIGHTS
        for light in lm:
            assert 0.0 <= light.u <= 1.0 and 0.0 <= light.v <= 1.0
            assert 1e-4 <= light.softness <= 0.1
            assert 0.0 <= light.intensity <= 3.0
    assert len(counts) > 10  # the number of lights varies
    small = LightMap.random(random.Random(5), max_lights=3)
    assert 1 <= len(small) <= 3
    # seeded: reproducible
    assert LightMap.random(random.Random(7)).lights == LightMap.random(random.Random(7)).lights


_NO_NUMPY = """
import sys, importlib.util
sys.modules['numpy'] = None  # any 'import numpy' now raises ImportError
{body}
assert sys.modules.get('numpy') is None
print('ok')
"""


def _run_without_numpy(body: str) -> subprocess.CompletedProcess:
    return subprocess.run(
        [sys.executable, "-c", _NO_NUMPY.format(body=body)], capture_output=True, text=True, timeout=60
    )


def test_blocking_numpy_really_blocks_it():
    result = _run_without_numpy("import numpy")
    assert result.returncode != 0 and "import of numpy halted" in result.stderr


def test_plugin_copy_of_shared_modules_imports_without_numpy(tmp_path):
    from ssn_engine.plugin_files import KIT_MODULES, copy_host_kit

    dest = copy_host_kit(tmp_path)
    assert {p.name for p in dest.iterdir()} == set(KIT_MODULES)
    body = f"""
sys.path.insert(0, {str(tmp_path)!r})
from host_kit import {", ".join(m.removesuffix(".py") for m in KIT_MODULES)}
import io
buf = io.BytesIO()
protocol.write_message(buf, {{'id': 1, 'cmd': 'hello'}}, {{'a': protocol.Buffer('uint8', (2, 2), b'abcd')}})
buf.seek(0)
header, buffers = protocol.read_message(buf)
assert header['cmd'] == 'hello' and bytes(buffers['a'].data) == b'abcd'
assert light_map.preset('high-sun').lights
assert client.EngineClient is not None
editor = light_editor.LightMapEditor(light_map.preset('softbox'))
editor.press(0.1, 0.2)
assert len(light_map_picture.map_rgb(editor.lights, 8, 4)) == 96
"""
    result = _run_without_numpy(body)
    assert result.returncode == 0, result.stderr
    assert result.stdout.strip() == "ok"


# -- disk lights: the `angle` of the light-map file -------------------------------------------------------------


def _file(*lights: dict) -> str:
    return json.dumps({"format": "ssn-shadow-elm", "version": 1, "lights": list(lights)})


def test_an_angle_light_is_read_written_and_read_again():
    lm = LightMap.from_json(_file({"u": 0.3, "v": 0.7, "angle": 0.53, "intensity": 2.0}))
    (light,) = lm.lights
    assert light.angle == 0.53 and light.size_degrees == 0.53
    assert light.softness == lm_mod.SOFTNESS_RANGE[0]  # a reader without angle gets the smallest Gaussian
    written = json.loads(lm.to_json())["lights"][0]
    assert written["angle"] == 0.53 and "softness" in written
    assert LightMap.from_json(lm.to_json()).lights == lm.lights


def test_a_light_with_both_is_the_disk_and_keeps_its_softness_for_old_readers():
    (light,) = LightMap.from_json(_file({"u": 0.3, "v": 0.7, "angle": 12, "softness": 0.004, "intensity": 1})).lights
    assert light.angle == 12 and light.size_degrees == 12
    assert json.loads(LightMap([light]).to_json())["lights"][0]["softness"] == 0.004


def test_old_softness_files_still_read_as_gaussians():
    (light,) = LightMap.from_json(_file({"u": 0.3, "v": 0.7, "softness": 0.002, "intensity": 1})).lights
    assert light.angle is None and light.softness == 0.002
    assert "angle" not in json.loads(LightMap([light]).to_json())["lights"][0]


@pytest.mark.parametrize(
    "light, message",
    [
        ({"u": 0.3, "v": 0.7, "intensity": 1}, r"lights\[0\]\.softness: missing .*softness or angle"),
        ({"u": 0.3, "v": 0.7, "angle": 0.0, "intensity": 1}, r"lights\[0\]\.angle: expected a number in \[0.1, 40\]"),
        ({"u": 0.3, "v": 0.7, "angle": 90, "intensity": 1}, r"lights\[0\]\.angle: expected a number in"),
        ({"u": 0.3, "v": 0.7, "angle": "big", "intensity": 1}, r"lights\[0\]\.angle: expected a number, got 'big'"),
        ({"u": 0.3, "v": 0.7, "angle": True, "intensity": 1}, r"lights\[0\]\.angle: expected a number"),
        ({"v": 0.7, "angle": 3, "intensity": 1}, r"lights\[0\]\.u: missing"),
    ],
)
def test_bad_angle_lights_are_refused_naming_the_field(light, message):
    with pytest.raises(LightMapError, match=message):
        LightMap.from_json(_file(light))


def test_resizing_a_disk_light_keeps_its_power_and_place():
    lm = LightMap()
    lm.add(0.3, 0.6, angle=0.53, intensity=2.0)
    power = lm.lights[0].power
    lm.set_angle(0, 12.0)
    light = lm.lights[0]
    assert (light.u, light.v, light.angle, light.intensity) == (0.3, 0.6, 12.0, 2.0)
    assert light.power == power
    lm.set_angle(0, 1000.0)
    assert lm.lights[0].angle == lm_mod.ANGLE_RANGE[1]


def test_a_disk_carries_the_power_of_the_reference_gaussian():
    """Conventions, "Light size": a disk of intensity I carries the solid-angle integral of radiance of a
    Gaussian of intensity I and softness 0.01, whatever its size."""
    for v in (0.2, 0.5, 0.8):
        gaussian = GaussianLight(0.4, v, lm_mod.REFERENCE_SOFTNESS, 1.5).power
        for angle in (0.53, 3.0, 12.0, 30.0):
            assert GaussianLight.disk(0.4, v, angle, 1.5).power == gaussian


def test_disk_directions_lie_within_the_disk_and_share_its_power():
    light = GaussianLight.disk(0.4, 0.5, 10.0)
    directions = lm_mod.disk_directions(light, 200)
    assert sum(share for _, _, share in directions) == pytest.approx(1.0)
    for u, v, _ in directions:  # within 5 degrees of the centre (0.4, 0.5): azimuth -36, elevation 45
        e, a = math.radians(90 * (1 - v)), math.radians(360 * u - 180)
        c = math.cos(math.radians(45)) * math.cos(e) * math.cos(a + math.radians(36)) + math.sin(
            math.radians(45)
        ) * math.sin(e)
        assert math.degrees(math.acos(min(1.0, c))) <= 5.0 + 1e-6


def test_the_sun_presets_are_disks():
    assert preset("sun").lights[0].angle == 0.53
    assert preset("hazy-sun").lights[0].angle == 3.0
    assert 12 <= preset("softbox").lights[0].angle <= 20
    for name in ("high-sun", "low-sun-left", "low-sun-right"):
        assert preset(name).lights[0].angle == 0.53


def test_a_softness_control_resizes_a_disk_light():
    """The hosts' softness slider on a disk light sets its diameter to the Gaussian's as wide, power kept."""
    lights = LightMap([GaussianLight.disk(0.3, 0.5, 0.53, 2.0)])
    lights.resize(0, 0.002)
    light = lights.lights[0]
    assert light.angle == pytest.approx(softness_angle(0.002)) and light.intensity == 2.0
    assert light.softness == pytest.approx(0.002)
