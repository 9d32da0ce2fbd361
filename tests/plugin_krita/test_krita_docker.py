"""The docker in a real Krita window (kritarunner) on a 1366 x 768 screen: its width, a short docker, and Krita's
undo."""

import pytest
from krita_helpers import run_in_fresh_profile

from plugin_krita.ssn_shadow.shared import light_map as lm

pytestmark = pytest.mark.krita


def test_the_docker_fits_krita_default_dock_and_follows_undo(tmp_path):
    data = run_in_fresh_profile(tmp_path, "krita_docker_driver")

    layout = data["layout"]
    assert layout["window"][2] == layout["screen"][2] * 2 // 3, layout  # a fresh profile's window
    # at Krita's default dock width the controls fit: no horizontal scroll bar, nothing cut off on the right;
    # and the docker does not widen the dock column much when it is added
    assert layout["docker_width"] == layout["layers_docker_width"] == layout["default_width"], layout
    assert layout["widened_to"] <= layout["default_width"] + 20, layout
    assert not layout["horizontal_scroll_bar"] and layout["body_min_width"] <= layout["viewport_width"], layout
    assert layout["map_right"] < layout["viewport_width"] and layout["presets_right"] < layout["viewport_width"]
    assert layout["generate_visible"], layout
    # and in a narrower dock too (Krita's font here; a larger one has 60 px to spare): the map scales down
    narrow = data["narrow"]
    assert narrow["docker_width"] == 260 and not narrow["horizontal_scroll_bar"], narrow
    assert narrow["map_right"] < narrow["viewport_width"], narrow

    # the docker as Krita's default workspace stacks it on a 1366 x 768 screen, 262 x 180: the map (the light
    # editor) and Generate in view without scrolling, the other sections folded
    short = data["short"]
    assert short["docker"][0] == 262 and short["docker"][1] <= 180, short  # shorter where the window is crowded
    assert short["map_in_view"] and short["generate_in_view"] and short["scrolled"] == 0, short
    assert not any(short["open"].values()), short

    first, second = data["undo"]
    assert second["names"] == ["Background", "Shadow: Person", "Person"], data["undo"]  # the first shadow is back
    # the cutout's layer stays active (the next brush stroke lands on it, not on the shadow brought back)
    assert first["active"] == second["active"] == "Person", data["undo"]
    # and the docker shows the lights that shadow was made with
    assert second["light_map"] == data["first_light_map"] == lm.preset("low-sun-left").to_dict()
    assert second["preset"] == "Low sun, left"
    # the Intensity box showed the selected light's intensity (the low sun's), and sets it
    assert data["intensity"] == {"shown": second["light_map"]["lights"][0]["intensity"], "light": 1.5}, data
