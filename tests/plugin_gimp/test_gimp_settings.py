"""Procedure arguments and settings validation, without GIMP."""

import json
import re
from pathlib import Path

import pytest
import ssn_settings as s
from ssn_settings import SettingsError, ShadowSettings, resolve_light_map

from ssn_engine.host_kit import camera_rules, geometry_clamp, light_map


def test_arguments_cover_every_setting():
    names = [a.name for a in s.ARGUMENTS]
    assert names == [
        "light-map",
        "shadow-color",
        "opacity",
        "ao-strength",
        "use-horizon",
        "horizon",
        "fov",
        "keep-whole-shadow",
        "lift",
        "thickness",
    ]
    for spec in s.ARGUMENTS:
        assert spec.kind in {"string", "double", "boolean", "color"}
        if spec.kind == "double":
            assert spec.lo <= spec.default <= spec.hi
    assert s.PROCEDURE_NAME == "plug-in-ssn-shadow"
    assert s.MENU_PATH == "<Image>/Filters/Light and Shadow"
    assert "Soft" in s.MENU_LABEL and "(SSN)" in s.MENU_LABEL


def test_the_procedures_help_and_docs_list_every_preset():
    """Issue item e: the procedure's help, its light-map argument's blurb and docs/gimp.md's table named seven of
    the nine presets (not sun and hazy-sun). The help and the blurb are made from the host kit's table; the page
    must list the same names, in its order."""
    names = list(light_map.PRESETS)
    assert {"sun", "hazy-sun"} <= set(names)
    listed = ", ".join(names)
    assert f"a preset ({listed}; default {light_map.DEFAULT_PRESET})" in s.PROCEDURE_HELP
    assert f"A preset name ({listed})" in s.ARG_BY_NAME["light-map"].blurb
    page = (Path(__file__).resolve().parents[2] / "docs" / "gimp.md").read_text(encoding="utf-8")
    row = next(line for line in page.splitlines() if line.startswith("| `light-map` |"))
    documented = re.search(r"a preset name \(([^)]*)\)", row)
    assert documented is not None, row
    assert re.findall(r"`([^`]+)`", documented[1]) == names, row


def test_mnemonics_do_not_clash_with_ok_and_cancel():
    taken = {"o", "c", "r", "g"}  # _OK, _Cancel, _Reset, From _guide
    keys = [spec.label[spec.label.index("_") + 1].lower() for spec in s.ARGUMENTS if spec.name != "light-map"]
    assert not taken & set(keys) and len(set(keys)) == len(keys)


@pytest.mark.parametrize("name", list(light_map.PRESETS))
def test_preset_names(name):
    assert resolve_light_map(name) == {"preset": name}
    assert resolve_light_map(f"  {name}\n") == {"preset": name}


def test_empty_means_default_preset():
    assert resolve_light_map("") == {"preset": light_map.DEFAULT_PRESET}


def test_json_light_map_round_trips():
    lm = light_map.LightMap([light_map.GaussianLight(0.3, 0.6, 0.01, 2.0)])
    params = resolve_light_map(lm.to_json())
    assert params == {"light_map": lm.to_dict()}
    assert s.editor_light_map(lm.to_json()).lights == lm.lights
    assert s.editor_light_map("overcast").lights == light_map.preset("overcast").lights


@pytest.mark.parametrize(
    "text, fragment",
    [
        ("sunset", "unknown preset 'sunset'"),
        ("{not json", "not valid JSON"),
        (
            json.dumps(
                {
                    "format": "ssn-shadow-elm",
                    "version": 1,
                    "lights": [{"u": 2, "v": 0, "softness": 0.01, "intensity": 1}],
                }
            ),
            "lights[0].u",
        ),
        (json.dumps({"format": "other", "version": 1, "lights": []}), "format"),
    ],
)
def test_bad_light_maps_name_the_problem(text, fragment):
    with pytest.raises(SettingsError) as err:
        resolve_light_map(text)
    assert fragment in str(err.value) and str(err.value).startswith("light-map:")


@pytest.mark.parametrize(
    "kwargs, fragment",
    [
        ({"opacity": 1.5}, "opacity"),
        ({"opacity": float("nan")}, "opacity"),
        ({"ao_strength": -1}, "ao-strength"),
        ({"ao_strength": 5}, "ao-strength"),
        ({"color": (0, 0)}, "shadow-color"),
        ({"color": (0, 2, 0)}, "shadow-color"),
        ({"light_map": "nope"}, "light-map"),
    ],
)
def test_settings_validation(kwargs, fragment):
    with pytest.raises(SettingsError, match=fragment):
        ShadowSettings(**kwargs)


def test_render_params_and_edits():
    st = ShadowSettings("low-sun-left", (0.2, 0.1, 0.0), 0.5, 1.0)
    assert st.render_params("uint16", (4000, 3000)) == {
        "preset": "low-sun-left",
        "color": [0.2, 0.1, 0.0],
        "opacity": 0.5,
        "format": {"dtype": "uint16", "channels": "rgba"},
        "clip": True,  # the canvas and a margin of a tenth of its larger side
        "margin": 400,
    }
    whole = ShadowSettings("low-sun-left", keep_whole=True).render_params("uint8", (4000, 3000))
    assert whole["clip"] is False and "margin" not in whole
    assert st.ao_edits() == []
    assert ShadowSettings(ao_strength=0.0).ao_edits() == [{"op": "strength", "value": 0.0}]
    assert ShadowSettings(ao_strength=2).ao_edits() == [{"op": "strength", "value": 2.0}]


def test_camera_only_with_a_horizon_and_scaled_for_the_preview():
    assert ShadowSettings().camera() is None
    st = ShadowSettings(horizon=300.0, fov=50.0)
    assert st.camera() == {"horizon": 300.0, "fov": 50.0}
    assert camera_rules.scaled_camera(st.camera(), 0.25) == {"horizon": 75.0, "fov": 50.0}
    with pytest.raises(SettingsError, match="fov"):
        ShadowSettings(horizon=10.0, fov=5.0)


def test_an_image_s_camera_arguments_are_its_own():
    """The camera arguments come from the image's record (scaled with the image), or are the horizon not given:
    never the last image's values, which GIMP keeps for every image."""
    values = {"use-horizon": True, "horizon": 380.0, "fov": 40.0, "opacity": 0.5}
    record = s.image_camera_record(values, 480)
    assert s.image_camera_arguments(record, 3000) == {"use-horizon": True, "horizon": 2375.0, "fov": 40.0}
    assert s.image_camera_arguments(None, 3000) == {
        "use-horizon": False,
        "horizon": s.ARG_BY_NAME["horizon"].default,
        "fov": s.ARG_BY_NAME["fov"].default,
    }
    assert set(s.image_camera_arguments(None, 10)) <= set(s.ARG_BY_NAME)


# -- the artist's geometry: lift and thickness -------------------------------------------------------------------
def test_lift_and_thickness_are_arguments_the_help_and_the_page_list():
    """Scripts and Ctrl+F set them: lift (pixels, >= 0, default 0) and thickness (-1, the default, or any value below
    0: read from the outline); the procedure's help and docs/gimp.md's table name both."""
    lift, thickness = s.ARG_BY_NAME["lift"], s.ARG_BY_NAME["thickness"]
    assert (lift.kind, lift.default, lift.lo) == ("double", 0.0, 0.0) and lift.hi >= 20 * 32768
    assert (thickness.kind, thickness.default, thickness.lo, thickness.hi) == ("double", -1.0, -1.0, 8.0)
    assert "-1 (any value below 0): read from the cutout's outline" in thickness.blurb
    assert "'lift'" in s.PROCEDURE_HELP and "'thickness'" in s.PROCEDURE_HELP and "-1" in s.PROCEDURE_HELP
    page = (Path(__file__).resolve().parents[2] / "docs" / "gimp.md").read_text(encoding="utf-8")
    rows = [line for line in page.splitlines() if line.startswith(("| `lift` |", "| `thickness` |"))]
    assert len(rows) == 2 and "read from the outline" in rows[1], rows


def test_geometry_settings_from_arguments():
    from ssn_core import ShadowError, settings_from_arguments

    st = settings_from_arguments({})
    assert (st.lift, st.thickness) == (0.0, None) and st.cutout_geometry() == {}  # the engine's defaults: none sent
    st = settings_from_arguments({"lift": 40, "thickness": -1.0})
    assert st.geometry() == {"lift": 40.0, "thickness": None} == st.cutout_geometry()
    assert settings_from_arguments({"thickness": -0.5}).thickness is None  # below 0: read
    assert settings_from_arguments({"thickness": 0.0}).thickness == 0.0  # flat, not read
    assert settings_from_arguments({"thickness": 2.5}).cutout_geometry() == {"lift": 0.0, "thickness": 2.5}
    for bad, name in (({"lift": -1.0}, "lift"), ({"lift": float("nan")}, "lift"), ({"thickness": 9.0}, "thickness")):
        with pytest.raises(ShadowError, match=name):
            settings_from_arguments(bad)
    with pytest.raises(ShadowError, match="thickness"):
        settings_from_arguments({"thickness": float("nan")})


def test_the_dialog_clamps_a_lift_and_says_why():
    """Hosts clamp and say why: past 20 canvas heights to 20; below 0 to 0; a lift leaving the ground beneath the
    object at or above the horizon (the engine refuses it) raised to the least whole row below it."""
    assert geometry_clamp.clamp_lift(12.0, 240) == (12.0, "")
    assert geometry_clamp.clamp_lift(0.0, 240, lowest=100, horizon=150) == (0.0, "")  # resting: always taken
    lift, why = geometry_clamp.clamp_lift(99999.0, 240)
    assert lift == 4800.0 and "more than 20 canvas heights (4800 px" in why and "set to 4800" in why
    lift, why = geometry_clamp.clamp_lift(-5.0, 240)
    assert lift == 0.0 and "set to 0" in why
    lift, why = geometry_clamp.clamp_lift(30.0, 240, lowest=100, horizon=150.5)
    assert lift == 51.0 and "at or above the horizon (row 150)" in why and "raised to 51" in why
    assert geometry_clamp.clamp_lift(51.0, 240, lowest=100, horizon=150.5) == (51.0, "")
    assert geometry_clamp.clamp_lift(30.0, 240, lowest=200, horizon=150) == (
        30.0,
        "",
    )  # its foot below the horizon already


def test_the_dialog_clamps_a_thickness_and_says_why():
    assert s.clamp_thickness(0.29) == (0.29, "")
    assert s.clamp_thickness(-3.0) == (s.READ_THICKNESS, "")  # below 0 reads from the outline: nothing to say
    value, why = s.clamp_thickness(12.0)
    assert value == 8.0 and "outside 0 (flat) to 8 (deep)" in why and "set to 8" in why
    value, why = s.clamp_thickness(float("nan"))
    assert value == s.READ_THICKNESS and "read from the outline" in why


def test_the_thickness_slider_puts_flat_round_and_deep_apart():
    assert s.thickness_from_slider(0.0) == 0.0 and s.thickness_from_slider(1.0) == 1.0
    assert s.thickness_from_slider(s.THICKNESS_SLIDER_TOP) == 8.0 and s.thickness_from_slider(99) == 8.0
    assert 0.3 < s.slider_from_thickness(1.0) / s.THICKNESS_SLIDER_TOP < 0.4
    assert s.thickness_from_slider(s.slider_from_thickness(0.29)) == 0.29
    assert s.thickness_read_text(0.2912) == "read 0.29"


def test_an_image_s_lift_and_thickness_are_its_own_and_scale_with_it():
    """Kept with each image (a parasite): the lift scales with the image's height; no record, another program's or a
    damaged one gives the defaults (resting, read), never another image's values."""
    record = s.image_geometry_record({"lift": 40.0, "thickness": 0.5, "opacity": 1.0}, 480)
    assert json.loads(record)["format"] == "ssn-shadow-geometry"
    assert s.image_geometry_arguments(record, 480) == {"lift": 40.0, "thickness": 0.5}
    assert s.image_geometry_arguments(record, 960) == {"lift": 80.0, "thickness": 0.5}
    read = s.image_geometry_record({"lift": 0.0, "thickness": -1.0}, 100)
    assert s.image_geometry_arguments(read, 100) == {"lift": 0.0, "thickness": -1.0}
    defaults = {"lift": 0.0, "thickness": -1.0}
    for text in (None, "", "{", '{"format": "other"}', record.replace('"height":480', '"height":0')):
        assert s.image_geometry_arguments(text, 480) == defaults, text
    assert set(defaults) <= set(s.ARG_BY_NAME)
