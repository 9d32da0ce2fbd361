"""Procedure arguments and settings validation, without GIMP."""

import json
import re
from pathlib import Path

import pytest
import ssn_settings as s
from ssn_settings import SettingsError, ShadowSettings, resolve_light_map

from ssn_engine.host_kit import camera_rules, light_map


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
