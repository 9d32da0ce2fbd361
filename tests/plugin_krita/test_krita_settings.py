"""The docker's settings travel with the .kra file: set in one Krita, saved, read back by a fresh Krita."""

import sys

import pytest
from krita_helpers import run_kritarunner

from plugin_krita.install import install
from plugin_krita.ssn_shadow.shared import light_map as lm

pytestmark = pytest.mark.krita


def test_settings_survive_saving_closing_and_reopening_the_kra(tmp_path):
    pykrita = tmp_path / "pykrita"
    install(dest=pykrita, python=sys.executable)
    kra = tmp_path / "settings.kra"
    env = {"SSN_TEST_KRA": str(kra)}
    first = run_kritarunner(pykrita, "krita_settings_driver", "save", tmp_path / "save.json", env)
    second = run_kritarunner(pykrita, "krita_settings_driver", "reopen", tmp_path / "reopen.json", env)

    new, edited = first["shown_new"], first["shown_set"]
    assert not new["panel"]["use_horizon"] and new["panel"]["opacity"] == 85  # a new image: the defaults
    expected = {
        "light_map": lm.preset("two-lights").to_dict(),
        "camera": {"horizon": 123.0, "fov": 58.0},
        "color": [0.2, 0.3, 0.9],
        "opacity": 0.4,
    }
    assert {key: edited["model"][key] for key in expected} == expected
    assert [op["op"] for op in edited["model"]["ao_edits"]] == ["grow", "brush", "brush", "strength"]
    assert edited["model"]["geometry"] == [40.0, 1.5] and new["model"]["geometry"] == [0.0, None]
    assert edited["panel"]["thickness_label"] == "Thickness: 1.50" and edited["panel"]["lift"] == 40

    # the settings change no pixel and add no undo step; they mark the image modified (closing asks to save)
    assert first["pixels_after_settings"] == first["pixels_before"]
    assert first["undo_after"] == first["undo_before"] and first["undo_before"] is not None
    assert first["modified_after_settings"] and first["saved"] and not first["modified_after_save"]

    # a fresh Krita opens the .kra: the docker shows the same settings, the pixels are the ones saved
    assert second["opened"] and second["pixels"] == first["pixels_before"]
    assert second["shown"]["model"] == edited["model"]
    assert second["shown"]["panel"] == edited["panel"]
    assert second["shown"]["panel"]["use_horizon"] and second["shown"]["panel"]["horizon"] == 123
    assert second["shown"]["status"][0] == "info"  # read without complaint
    assert not second["modified_after_reading"]  # reading the settings is no change
    # the docker on the active (reopened) document shows them too, one model per document across view changes
    assert second["active_is_opened"] and second["docker_same_model"]
    assert second["docker_shown"] == second["shown"]

    # the reopened lift casts the shadow lower: its top row lies further down than with the lift box set to 0
    lifted, resting = second["lifted"], second["resting"]
    assert lifted["top"] is not None and resting["top"] is not None, second
    assert lifted["top"] >= resting["top"] + 15, (lifted, resting)
    assert second["lift_after"] == 0.0 and resting["status"][0] == "info", resting
