"""The plug-in inside real Krita (kritarunner), against the real engine worker.

Needs Debian's krita (kritarunner) and, for undo, xvfb-run: Krita's undo
action exists only with a window, which kritarunner can open on an X
server but not on the offscreen platform. Skips only outside CI.
"""

import sys
from pathlib import Path

import pytest
from krita_helpers import run_kritarunner

from plugin_krita.install import install

pytestmark = pytest.mark.krita


@pytest.fixture(scope="module")
def pykrita(tmp_path_factory):
    dest = tmp_path_factory.mktemp("pykrita")
    install(dest=dest, python=sys.executable)
    return dest


def run_in_krita(pykrita: Path, depth: str, result: Path) -> dict:
    env = {"SSN_TEST_DEPTHS": depth, "SSN_TEST_WINDOW": "1"}
    data = run_kritarunner(pykrita, "krita_driver", "main", result, env)
    return data["cases"][depth]


def _check_shadow(state: dict, side: str) -> None:
    names = state["names"]
    assert names.count("Shadow: Person") == 1, names
    assert state["shadow_index"] == state["source_index"] - 1, names  # directly below the source
    assert state["blend"] == "normal" and state["type"] == "paintlayer"  # black: Normal, the same as Multiply
    assert state["below"]["sum"] > 100, state  # shadow on the ground in front of the object
    assert state[side]["sum"] > 100, state  # and beside it, away from the light
    other = "left" if side == "right" else "right"
    assert state[other]["sum"] < 0.15 * state[side]["sum"], state  # the lit side: a faint contact shadow at most
    assert state["far_above"]["max"] == 0.0, state  # none far above it


@pytest.mark.parametrize("depth", ["U8", "U16", "F16", "F32"])
def test_generate_in_real_krita(pykrita, tmp_path, depth):
    case = run_in_krita(pykrita, depth, tmp_path / f"result-{depth}.json")
    errors = [m for m in case["messages"] if m[0] == "error"]
    assert not errors, errors

    first, second = case["after_first"], case["after_second"]
    # the cutout's layer stays the active one (issue #14, item 1: with a window the new shadow layer took over,
    # so the next brush stroke landed on the shadow)
    assert case["active_after_first"] == "Person"
    _check_shadow(first, "right")  # low-sun-left: light left of centre, shadow to the right
    _check_shadow(second, "left")  # low-sun-right: shadow to the left
    # the second generate updates that layer: still one shadow layer in the same place, new pixels
    assert second["names"] == first["names"] == ["Background", "Shadow: Person", "Person"]
    assert second["left"]["sum"] > 5 * first["left"]["sum"] and second["left"]["sum"] > 100
    # ... although the worker died before it (issue #14, item 3: that click failed with "unknown cutout")
    assert not [m for m in case["messages_after_worker_death"] if m[0] == "error"], case["messages_after_worker_death"]

    assert case["source_identical"] and case["background_identical"]
    assert case["selection_before"] is False and case["selection_after"] is False

    assert case["undo_available"], "Krita's edit_undo action is missing (no window?)"
    steps = [names for _text, names in case["undo_steps"]]
    assert steps[0] == ["Background", "Person"]  # one Ctrl+Z removes the new shadow layer
    assert steps[1] == ["Background", "Shadow: Person", "Person"]  # the next brings the previous one back
    assert steps[2] == ["Background", "Person"]  # and the next removes that one
    assert case["source_identical_after_undo"]

    if depth == "U8":
        sel = case["with_selection"]
        assert sel["shadow_index"] == sel["source_index"] - 1
        # half the cutout selected (its left half, the low sun from the left): a smaller shadow, narrower (the
        # camera read from the half's own outline, so not exactly as long)
        assert sel["total"]["sum"] < 0.95 * first["total"]["sum"]
        assert case["selection_unchanged"] and case["source_identical_after_selection"]
        # Select All (issue #14, item 4): refused with a warning instead of a shadow over the whole picture
        assert any("whole canvas" in text for level, text in case["select_all_messages"] if level == "warning")
        assert case["select_all_unchanged"]
        # the lowest layer of its group: the shadow goes above it (with a notice), and Generate works again
        assert not [m for m in case["lowest_layer_messages"] if m[0] == "error"], case["lowest_layer_messages"]
        assert case["lowest_layer_names"] == ["Person", "Shadow: Person"]
        # ... also with the shadow layer active: it names its cutout, and that shadow is replaced, not doubled
        assert case["lowest_layer_renders"] == 3, case["lowest_layer_all_messages"]
        assert case["lowest_layer_names_from_shadow"] == ["Person", "Shadow: Person"]
        # and the usual shadow below its cutout, active, names that cutout too
        refused = [m for m in case["from_shadow_messages"] if m[0] in ("error", "warning")]
        assert not refused, refused
        names = case["from_shadow_names"]  # (Krita adds a "Selection Mask" node for the empty selection)
        assert names.count("Shadow: Person") == 1 and names.index("Shadow: Person") == names.index("Person") - 1
        # the horizon from a guide (issue #14, horizon control): a different shadow, still one layer
        # (the field of view the engine read from the outline, which the docker showed, stays)
        assert case["camera_read"] is not None
        assert case["camera_from_guide"] == {"horizon": 40.0, "fov": float(round(case["camera_read"]["fov"]))}
        before, after = case["before_camera"], case["with_camera"]
        assert after["names"].count("Shadow: Person") == 1
        assert after["total"] != before["total"], (before["total"], after["total"])
        # docked 650 px tall: the controls keep their full height and scroll, they do not overlap; Generate
        # stays in view below them
        docker = case["docker"]
        assert docker["scrolls"] and docker["panel_height"] >= docker["panel_min_height"], docker
        assert docker["scroll_range"] > 0 and docker["generate_shown"], docker
    # A light drag: the docker previews it on a thumbnail of the image without the old shadow (hidden in a
    # clone of the document), the canvas is left alone, and the release writes the layer as one undo step
    drag = case["drag"]
    assert drag["background_size"] == [320, 240], drag
    low, high = drag["background_under_shadow"]
    assert high - low <= 2 and drag["canvas_under_shadow_min"] < low - 20, drag  # the old shadow: not in it
    assert drag["previews"] >= 2 and drag["preview_size"] == [320, 240], drag
    assert drag["preview_under_shadow_min"] < low - 20, drag  # the new shadow on the thumbnail
    assert drag["writes_during"] == 0 and drag["canvas_unchanged_during"], drag
    assert drag["documents_unchanged"] and drag["shadow_visible"] and drag["active"] == "Person", drag
    # the drag's undo step is taken at its start (the shadow layer replaced by a copy: the same pixels), so the
    # release writes in place (one recomposite of the image, not the two of a replacement), exactly the pixels the
    # worker rendered in the document's depth; Ctrl+Z once: no shadow, twice: the shadow before the drag
    assert drag["replaced_at_start"] and drag["writes_after"] == 1 and not drag["release_created"], drag
    assert drag["changed_after"] and drag["release_pixels_exact"] and drag["release_within_rect"], drag
    assert "Shadow: Person" not in drag["after_one_undo"] and "Person" in drag["after_one_undo"], drag
    assert drag["after_two_undos_is_before"], drag
    assert all(level == "info" for level, _ in drag["messages"]), drag
    # the black shadow's Normal layer gives the picture a Multiply layer gives (within one 8-bit step), and a
    # coloured shadow is written in Multiply
    modes = case["black_shadow_modes"]
    assert modes["normal"]["mode"] == "normal"
    normal, multiply = modes["normal"]["reds"], modes["multiply"]["reds"]
    assert min(normal) < max(normal) - 20 and max(abs(a - b) for a, b in zip(normal, multiply, strict=True)) <= 1
    coloured = case["coloured"]
    assert coloured["blend"] == "multiply" and coloured["names"].count("Shadow: Person") == 1, coloured
