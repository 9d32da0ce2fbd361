"""A light's size in degrees, typed into the docker's Size box in a real Krita window (kritarunner)."""

import pytest
from krita_helpers import run_in_fresh_profile


pytestmark = pytest.mark.krita


def test_the_size_box_makes_a_05_degree_sun_and_its_shadow_is_crisper_than_at_12(tmp_path):
    data = run_in_fresh_profile(tmp_path, "krita_size_driver")
    assert data.get("done"), data.get("error")

    assert data["preset_size"] == 0.53  # the Sun preset's light
    soft, sun = data["sizes"]["12"], data["sizes"]["0.53"]
    assert soft["box"] == 12.0 and [light["angle"] for light in soft["lights"]] == [12.0]
    assert sun["box"] == 0.53 and [light["angle"] for light in sun["lights"]] == [0.53]
    assert sun["map_lights"] == sun["lights"]  # the map shows the lights the shadow was made with
    # resizing keeps the light's power: the same intensity; and a shadow of about the same darkness
    assert sun["lights"][0]["intensity"] == soft["lights"][0]["intensity"]
    assert soft["darkness"] > 0 and sun["darkness"] > 0
    # and the sun's shadow is crisp where the softbox-sized light's is soft
    assert sun["crispness"] > 2.0 * soft["crispness"], data["sizes"]
