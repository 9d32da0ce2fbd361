"""The docker's per-document model and its settings saved in the document, without Krita."""

import json

import pytest
from krita_helpers import FakeDocument, FakeHost

from plugin_krita.ssn_shadow.model import MAX_SHADOW_RECORDS, READY, ShadowModel
from plugin_krita.ssn_shadow.persistence import ANNOTATION, DocumentModels, SettingsError, dump, restore
from plugin_krita.ssn_shadow.shared import light_map as lm


def record(model):
    edits, saved = [], []
    model.edited.connect(lambda what, step: edits.append((what, step)))
    model.modified.connect(saved.append)
    return edits, saved


def test_a_change_is_signalled_once_and_derived_state_is_read_only(qapp):
    m = ShadowModel()
    shown = []
    m.opacity_changed.connect(shown.append)
    edits, saved = record(m)
    m.opacity = 0.5
    m.opacity = 0.5  # the same value: nothing
    assert shown == [0.5] and edits == [("opacity", True)] and saved == ["opacity"]
    assert m.status == ("info", READY)
    with pytest.raises(AttributeError, match="derived state"):
        m.status = ("error", "x")  # type: ignore[misc]
    m.report_status("warning", "careful")
    assert m.status == ("warning", "careful") and len(edits) == 1  # a report is no edit


def test_a_slider_drag_is_one_undo_step(qapp):
    m = ShadowModel()
    edits, _ = record(m)
    m.begin_stroke()
    for value in (0.5, 0.6, 0.7):
        m.opacity = value
    m.end_stroke()
    m.opacity = 0.8  # a key press: its own step
    assert edits == [("opacity", True), ("opacity", False), ("opacity", False), ("opacity", True)]


def test_the_camera_is_edited_only_when_the_horizon_is_given(qapp):
    m = ShadowModel()
    edits, saved = record(m)
    m.horizon = 300.0  # remembered, but the engine still reads the camera itself
    assert m.camera is None and edits == [] and saved == ["horizon"]
    m.use_horizon = True
    assert m.camera == {"horizon": 300.0, "fov": 45.0} and edits == [("camera", True)]
    m.fov = 50.0
    assert edits[-1] == ("camera", True) and m.camera == {"horizon": 300.0, "fov": 50.0}
    m.use_horizon = False
    m.report_camera_read({"horizon": 411.6, "fov": 38.2})  # shown in the fields; no edit, nothing saved
    assert (m.horizon, m.fov, m.camera) == (412.0, 38.0, None) and len(saved) == 4
    m.use_horizon = True  # giving the horizon starts from the one read
    assert m.camera == {"horizon": 412.0, "fov": 38.0} and edits[-1] == ("camera", True)


def test_a_light_drag_and_its_release_are_edits_even_when_the_map_is_unchanged(qapp):
    m = ShadowModel()
    edits, saved = record(m)
    light_map = m.light_map.copy()
    light_map.move(0, 0.3, 0.4)
    m.edit_light_map(light_map, True, dragging=True)
    assert m.light_dragging and m.light_map == light_map and m.light_map is not light_map
    m.edit_light_map(light_map, False)  # the release where the drag left it
    assert not m.light_dragging and edits == [("light_map", True), ("light_map", False)] and saved == ["light_map"]


def settings_of(m):
    return (m.light_map, m.use_horizon, m.horizon, m.fov, m.color, m.opacity, m.ao_edits.steps, m.ao_strength)


def edit_everything(m):
    m.light_map = lm.preset("two-lights")
    m.horizon, m.fov, m.use_horizon = 413.0, 60.0, True
    m.color, m.opacity = (0.2, 0.1, 0.4), 0.6
    m.brush_ao(0.5, 0.8, 0.05, -0.5, True)
    m.brush_ao(0.52, 0.8, 0.05, -0.5, False)
    m.grow_ao(2)
    m.ao_strength = 1.5


def test_settings_are_saved_in_the_document_and_read_back_by_a_new_docker(qapp):
    """Each change writes the document's annotation; a docker that meets the document later (Krita restarted,
    the .kra reopened) shows the same settings, and reading them writes nothing."""
    host = FakeHost()
    m = DocumentModels(host).model_for(host.document)
    edit_everything(m)
    description, data = host.document.annotations[ANNOTATION]
    assert "Soft Shadow" in description and json.loads(data)["horizon"] == {"given": True, "row": 413.0, "fov": 60.0}

    writes = []
    host.set_annotation = lambda *args: writes.append(args)
    again = DocumentModels(host).model_for(host.document)
    assert settings_of(again) == settings_of(m) and again is not m
    assert again.ao_edit_list() == m.ao_edit_list() and len(again.ao_edit_list()) == 4
    assert again.camera == {"horizon": 413.0, "fov": 60.0}
    assert writes == []  # reading is no change: the document is not marked modified


def test_each_document_has_its_own_model_and_a_closed_one_is_forgotten(qapp):
    host = FakeHost()
    models = DocumentModels(host)
    first, other = host.document, FakeDocument("b.kra")
    models.model_for(first).opacity = 0.3
    assert models.model_for(other).opacity == 0.85 and models.model_for(first).opacity == 0.3
    assert ANNOTATION not in other.annotations  # nothing changed there: nothing written
    old = models.model_for(first)
    host.closed.append(first)
    assert models.model_for(other) is not None and all(d is not first for d, _ in models._models)
    assert models.model_for(None) is not models.model_for(None)  # no document: a model saved nowhere
    assert old.opacity == 0.3


def test_the_model_of_a_closed_document_is_known_as_closed(qapp):
    """The docker asks, when Krita closes a view, whether the document it shows is gone (then it shows the
    active document's state instead of the closed one's message)."""
    host = FakeHost()
    models = DocumentModels(host)
    first, other = host.document, FakeDocument("b.kra")
    shown, kept = models.model_for(first), models.model_for(other)
    shown.report_status("error", "the shadow engine exited")
    assert not models.is_closed(shown) and not models.is_closed(ShadowModel())
    host.closed.append(first)
    assert models.is_closed(shown) and not models.is_closed(kept)
    assert models.model_for(None).status == ("info", READY)  # what the docker shows where no image is left


@pytest.mark.parametrize(
    ("change", "message"),
    [
        (lambda s: s.update(opacity=2), "opacity: expected a number in [0, 1], got 2"),
        (lambda s: s.update(format="other"), "format: expected 'ssn-shadow-krita-settings'"),
        (lambda s: s.update(version=2), "version: this Soft Shadow reads version 1, got 2"),
        (lambda s: s["horizon"].update(given="yes"), "horizon.given: expected true or false"),
        (lambda s: s["horizon"].update(fov=500), "horizon.fov: expected a number in [10, 120]"),
        (lambda s: s.update(color=[0, 0]), "color: expected [red, green, blue]"),
        (lambda s: s["light_map"]["lights"][0].pop("u"), "light_map: lights[0].u: missing"),
        (lambda s: s["ao_edits"].update(steps=[[{"op": "paint"}]]), "ao_edits.steps[0][0]: expected a 'brush'"),
        (lambda s: s["ao_edits"].update(strength=None), "ao_edits.strength: expected a number, got None"),
    ],
)
def test_bad_saved_settings_name_the_field_and_change_nothing(qapp, change, message):
    source = ShadowModel()
    edit_everything(source)
    settings = json.loads(dump(source))
    change(settings)
    target = ShadowModel()
    before = settings_of(target)
    with pytest.raises(SettingsError) as info:
        restore(target, json.dumps(settings).encode())
    assert message in str(info.value)
    assert settings_of(target) == before  # all or nothing


def test_unreadable_settings_are_kept_in_the_document_until_a_change(qapp):
    host = FakeHost()
    host.document.annotations[ANNOTATION] = ("Soft Shadow", b"{not json")
    m = DocumentModels(host).model_for(host.document)
    level, text = m.status
    assert level == "warning" and "cannot be read (not JSON" in text and m.opacity == 0.85
    assert host.document.annotations[ANNOTATION][1] == b"{not json"  # not overwritten by a mere look
    m.opacity = 0.5
    assert json.loads(host.document.annotations[ANNOTATION][1])["opacity"] == 0.5


def test_a_widget_that_rounds_a_loaded_value_does_not_change_it(qapp):
    """The opacity slider shows whole percent: a loaded 0.333 shows as 33 and stays 0.333 (no save, no render)."""
    from test_ui import NoEngine

    from plugin_krita.ssn_shadow.controller import ShadowController
    from plugin_krita.ssn_shadow.ui.panel import ShadowPanel

    host = FakeHost()
    source = ShadowModel()
    source.opacity = 0.333
    host.document.annotations[ANNOTATION] = ("Soft Shadow", dump(source))
    m = DocumentModels(host).model_for(host.document)
    edits, saved = record(m)
    panel = ShadowPanel(ShadowController(NoEngine(), host, m))
    assert panel.opacity.value() == 33 and m.opacity == 0.333 and not edits and not saved


def test_shadow_records_are_saved_and_read_back(qapp):
    """The settings each shadow layer was made from travel with the document; a broken record is dropped."""
    m = ShadowModel()
    saved = []
    m.modified.connect(saved.append)
    m.light_map = lm.preset("two-lights")
    m.record_shadow("layer-a", m.settings())
    m.record_shadow("layer-a", m.settings())  # the same: no change
    assert saved == ["light_map", "shadows"]
    data = json.loads(dump(m))
    data["shadows"]["layer-b"] = {"light_map": "nonsense"}
    back = ShadowModel()
    restore(back, json.dumps(data).encode())
    assert list(back.shadows) == ["layer-a"] and back.shadows["layer-a"].light_map == lm.preset("two-lights")
    for i in range(MAX_SHADOW_RECORDS + 3):
        m.record_shadow(f"layer-{i}", m.settings())
    assert len(m.shadows) == MAX_SHADOW_RECORDS and "layer-a" not in m.shadows


def test_lift_and_thickness_are_clamped_with_the_reason_and_a_drag_is_one_edit(qapp):
    """The lift and thickness controls' edits: out of range clamped (0 to 20 canvas heights, a ground below the
    horizon of the camera in use; thickness 0 to 8) with the reason in the status; a drag's moves are previewed
    (``dragging``) and its release is an edit even where the value is unchanged; Reset is one edit."""
    m = ShadowModel()
    edits, saved = record(m)
    m.edit_lift(-5)  # no cutout yet: only the sign is known
    assert (
        m.lift == 0.0
        and m.status[0] == "warning"
        and "set to 0 (it rests on the ground)" in m.status[1]
        and edits == []
    )
    m.report_ground([120, 60, 200, 180], (320, 240), 170)  # its lift counts from row 170 (a soft edge below it)
    m.edit_lift(10_000)
    assert m.lift == 4800.0 and "(4800 px, the most the engine takes); set to 4800" in m.status[1]  # 20 canvas heights
    m.horizon, m.use_horizon = 300.0, True  # a horizon below the object: its ground lies lower still
    m.edit_lift(40)
    assert m.lift == 131.0 and "at or above the horizon (row 300)" in m.status[1], m.status
    m.edit_lift(0)  # resting on the ground is always taken
    assert m.lift == 0.0
    edits.clear()
    saved.clear()
    m.edit_lift(130, False, dragging=True)
    m.edit_lift(140, False, dragging=True)
    assert m.dragging("geometry") and not m.dragging("light_map") and m.lift == 140.0
    m.edit_lift(140, False)  # the release where the drag left it
    assert not m.dragging("geometry")
    assert edits == [("geometry", False)] * 3 and saved == ["geometry"] * 2
    m.edit_lift(140)  # no change: no edit
    assert len(edits) == 3

    m.edit_thickness(12.0)
    assert m.thickness == 8.0 and "0 (flat) to 8 (deep), the engine's range; set to 8" in m.status[1]
    m.report_geometry({"lift": 140.0, "thickness": 8.0, "thickness_read": 0.29})
    assert m.thickness_read == 0.29 and edits[-1] == ("geometry", True)
    with pytest.raises(AttributeError):
        m.thickness_read = 1.0  # derived: shown, not set
    edits.clear()
    m.reset_geometry()
    assert (m.lift, m.thickness) == (0.0, None) and edits == [("geometry", True)]
    m.lift = 12.0  # a plain assignment is an edit too
    assert edits[-1] == ("geometry", True)

    m.use_horizon = False  # the camera read: the lift is clamped to its horizon when the cutout is analysed
    m.report_camera_read({"horizon": 200.0, "fov": 40.0})
    edits.clear()
    assert m.clamp_geometry() and m.lift == 31.0 and edits == [] and saved[-1] == "geometry"
    assert not m.clamp_geometry()


def test_lift_and_thickness_are_saved_with_the_document_and_an_older_file_reads_as_resting(qapp):
    host = FakeHost()
    m = DocumentModels(host).model_for(host.document)
    m.edit_lift(40.0)
    m.edit_thickness(1.5)
    data = json.loads(host.document.annotations[ANNOTATION][1])
    assert data["geometry"] == {"lift": 40.0, "thickness": 1.5}
    again = DocumentModels(host).model_for(host.document)
    assert (again.lift, again.thickness) == (40.0, 1.5) and again.settings() == m.settings()
    m.reset_geometry()
    assert json.loads(host.document.annotations[ANNOTATION][1])["geometry"] == {"lift": 0.0, "thickness": None}
    assert DocumentModels(host).model_for(host.document).thickness is None

    del data["geometry"]  # saved before the geometry: on the ground, the thickness read
    older = ShadowModel()
    older.lift = 7.0
    restore(older, json.dumps(data).encode())
    assert (older.lift, older.thickness) == (0.0, None)
    for bad, message in (({"lift": -1}, "geometry.lift"), ({"lift": 0, "thickness": 9}, "geometry.thickness")):
        with pytest.raises(SettingsError, match=message):
            restore(ShadowModel(), json.dumps({**data, "geometry": bad}).encode())

    # an undo brings back the lift and thickness a shadow layer was made with
    m.edit_lift(30.0)
    m.record_shadow("layer-a", m.settings())
    m.edit_lift(60.0)
    assert m.shadow_shown("layer-a") is not None and m.lift == 30.0
