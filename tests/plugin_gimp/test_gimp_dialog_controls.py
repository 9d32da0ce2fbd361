"""Real GIMP 3: the filter's dialog worked as a user would (issue #41, GIMP defects 10, 11 and 12).

One gimp-console session under Xvfb on a 1366 x 768 screen opens the dialog several times, and another on a
768 x 1366 portrait screen twice (gimp_dialog_controls_check.py); inside the plug-in, gimp_dialog_steps.py (run by the
SSN_SHADOW_DIALOG_SELFTEST hook) drags lights, clicks the preview, the From guide button, the horizon box,
Reset and its popover's items with real pointer events (xdotool), and reports what the dialog showed.
"""

from __future__ import annotations

import json
import shutil
import tempfile
from pathlib import Path

import pytest
from test_gimp_integration import chroot, kit_on_path, run_gimp, worker  # noqa: F401 - the fixtures, shared

from plugin_gimp.install import install
from ssn_engine.host_kit.camera_rules import NO_GUIDE, row_from_preview
from ssn_engine.host_kit.light_editor import NEW_INTENSITY
from ssn_engine.host_kit.light_map import SUN, LightMap, preset

pytestmark = pytest.mark.gimp

HERE = Path(__file__).resolve().parent
SCREEN = (1366, 768)
NARROW_SCREEN = (768, 1366)  # a portrait screen (issue item d: the 850-pixel-wide dialog pushed OK off it)
MAX_HEIGHT = 700  # the dialog, with a title bar, a panel and room to spare, on a 1366 x 768 screen


def _session(root: Path, address: tuple, screen: tuple[int, int], run_set: str) -> tuple[list[dict], list[dict], str]:
    """Run the GIMP session of ``run_set`` ("wide" or "narrow") in the chroot ``root`` with the worker at
    ``address`` (port, token) on a ``screen`` (width, height): (the dialog's reports by run, GIMP's outcome of each
    run, the log)."""
    port, token = address
    work = Path(tempfile.mkdtemp(prefix="ssn-gimp-controls-", dir=root / "tmp"))
    inner = "/tmp/" + work.name
    try:
        install(work / "profile" / "plug-ins" / "ssn-shadow", address=("127.0.0.1", port), token=token)
        (work / "out").mkdir()
        shutil.copy(HERE / "gimp_dialog_controls_check.py", work / "check.py")
        shutil.copy(HERE / "gimp_dialog_steps.py", work / "steps.py")
        run, seconds = run_gimp(
            inner,
            kit_on_path(work, inner)
            + f'RUN_SET = "{run_set}"; SCRIPT_PATH = "{inner}/check.py"; exec(open(SCRIPT_PATH).read())',
            SSN_GIMP_XVFB="1",
            SSN_GIMP_SCREEN=f"{screen[0]}x{screen[1]}x24",
            SSN_SHADOW_DIALOG_SELFTEST=f"{inner}/steps.py",
        )
        log = run.stdout + run.stderr
        print(f"\ngimp-console dialog-controls session ({run_set}, {screen[0]} x {screen[1]}): {seconds:.1f} s")
        steps_path, runs_path = work / "out" / "steps.jsonl", work / "out" / "runs.jsonl"
        assert steps_path.exists() and runs_path.exists(), log[-6000:]
        steps = [json.loads(line) for line in steps_path.read_text().splitlines()]
        runs = [json.loads(line) for line in runs_path.read_text().splitlines()]
        for outcome in runs:
            assert "exception" not in outcome, outcome["exception"]
        return steps, runs, log
    finally:
        shutil.rmtree(work, ignore_errors=True)


@pytest.fixture(scope="module")
def session(chroot, worker):  # noqa: F811 - the fixtures above
    """Every run but the narrow screen's, once, on a 1366 x 768 screen."""
    return _session(chroot, worker, SCREEN, "wide")


@pytest.fixture(scope="module")
def narrow_session(chroot, worker):  # noqa: F811 - the fixtures above
    """The layout runs on a 768 x 1366 portrait screen."""
    return _session(chroot, worker, NARROW_SCREEN, "narrow")


def _run(steps: list[dict], name: str, index: int = 0) -> dict:
    """What the dialog showed in the ``index``-th run called ``name``; a run that stopped fails here."""
    run = [step for step in steps if step["run"] == name][index]
    assert "error" not in run, run["error"]
    return run


def _shows_the_camera_read(shown: dict) -> bool:
    """The horizon box unticked and its two fields holding the camera the note under the preview names."""
    return not shown["use"] and shown["note_camera"] == [round(shown["horizon"]), round(shown["fov"])]


def _fields_disabled(shown: dict) -> bool:
    """The row and field of view take no input."""
    return not shown["row_sensitive"] and not shown["fov_sensitive"]


def test_reset_restores_every_control(session):
    """Defect 10: a light dragged on the map, then Reset > Reset to Initial Values: the map, the preset box and the
    camera fields are back as the dialog opened (the fields agreeing with the camera note); then another preset, a
    drag, the horizon box ticked and a row clicked, then Reset > Reset to Factory Defaults: the default preset, by
    name, and the horizon not given, its fields showing the camera read."""
    run = _run(session[0], "reset")
    initial, dragged, after = run["initial"], run["dragged"], run["after_initial"]
    assert initial["label"] == "softbox" and initial["map"] == preset("softbox").to_dict()
    assert initial["target"] == 'Casting the shadow of the layer "Pawn".'  # no selection: the layer's alpha
    assert _shows_the_camera_read(initial), initial
    assert dragged["map"] != initial["map"] and dragged["label"] == "(custom)"  # the drag reached the map
    assert after["map"] == initial["map"], after["map"]
    assert after["label"] == "softbox"
    assert _shows_the_camera_read(after), after
    edited, factory = run["edited"], run["after_factory"]
    assert edited["label"] == "(custom)" and edited["map"] != initial["map"]
    assert edited["use"] and edited["horizon"] == 40.0  # the preview at scale 1: row 40
    assert factory["map"] == preset("softbox").to_dict(), factory["map"]
    assert factory["label"] == "softbox"
    assert _shows_the_camera_read(factory), factory
    assert session[1][0] == {
        "run": "reset",
        "status": "cancel",
        "layers": ["Pawn", "Background"],
        "camera_record": None,
    }


def test_the_dialog_fits_a_1366_x_768_screen_and_wraps_long_messages(session):
    """Defect 11: a portrait (480 x 640) and a landscape (640 x 480) image give a dialog at most 700 pixels tall
    with its buttons on the screen; a layer with a 160-character name that casts nothing gives a long error, which
    wraps instead of widening the dialog past the landscape image's."""
    portrait, landscape, faint = (_run(session[0], "layout", i)["shown"] for i in range(3))
    print(f"\n1366 x 768: dialog {portrait['size']} (portrait image), {landscape['size']} (landscape)")
    for shown in (portrait, landscape, faint):
        width, height = shown["size"]
        assert width <= SCREEN[0] and height <= MAX_HEIGHT, shown["size"]
        assert not shown["stacked"] and not shown["scrolled"]  # the light map beside the preview
    assert "is fully transparent" in faint["note"] and faint["note_lines"] >= 5, faint
    assert faint["size"][0] <= landscape["size"][0], (faint["size"], landscape["size"])
    assert portrait["preview"][1] <= 288 and landscape["preview"] == [384, 288]  # at most 384 x 288


def test_the_horizon_is_each_image_s_own_from_a_guide_or_a_click(session):
    """Defect 12: the row and field of view take input only while the box is ticked; From guide puts the horizon
    on the image's horizontal guide, a click on the preview on the clicked row; OK keeps it with the image. Another
    image opens with the horizon not given (the fields show its own camera read, not the first image's row), and
    From guide there, without a guide, says how to add one. The first image, scaled by 2, opens with its row
    scaled."""
    first = _run(session[0], "horizon-first")
    assert _shows_the_camera_read(first["initial"]) and _fields_disabled(first["initial"]), first["initial"]
    guide = first["from_guide"]
    assert guide["use"] and guide["horizon"] == 300.0 and guide["row_sensitive"] and guide["fov_sensitive"]
    assert first["clicked"]["use"] and first["clicked"]["horizon"] == row_from_preview(100, first["scale"])
    unticked = first["unticked"]
    assert _shows_the_camera_read(unticked) and _fields_disabled(unticked), unticked
    again = first["clicked_again"]
    assert again["use"] and again["horizon"] == row_from_preview(228, first["scale"]) == 380.0
    runs = {outcome["run"]: outcome for outcome in session[1]}
    assert runs["horizon-first"]["status"] == "success"
    record = json.loads(runs["horizon-first"]["camera_record"])
    assert record["given"] and record["horizon"] == 380.0 and record["height"] == 480
    second = _run(session[0], "horizon-second")
    assert _shows_the_camera_read(second["initial"]) and second["initial"]["horizon"] != 380.0, second["initial"]
    assert _fields_disabled(second["initial"])
    assert second["from_guide"]["note"] == NO_GUIDE and not second["from_guide"]["use"]
    scaled = _run(session[0], "horizon-again")["initial"]
    assert scaled["use"] and scaled["horizon"] == 760.0 and scaled["row_sensitive"], scaled


def test_the_dialog_says_it_casts_the_selection_when_one_is_left_over(session):
    """Issue item a: a 100 x 60 rectangle selected on the pawn's image; the dialog said 'the layer "Pawn"' while
    the filter cast the rectangle. It must name the selection and its size, as the cutout it reads is."""
    run = _run(session[0], "selection")
    target = run["shown"]["target"]
    assert target.startswith('Casting the shadow of the selection (100 x 60 pixels) in "Pawn".'), target
    assert "Select > None" in target
    assert run["cutout_source"] == "the selection"
    outcome = next(outcome for outcome in session[1] if outcome["run"] == "selection")
    assert outcome["status"] == "success" and outcome["layers"] == ["Pawn", "Shadow: Pawn", "Background"], outcome


def test_a_click_adds_the_presets_light_and_the_intensity_is_a_number(session):
    """Issue items b and c: with the sun preset chosen, a click on empty sky adds a disk of the sun's 0.53 degrees
    (it added a 36-degree Gaussian); the selected light's intensity shows in the Intensity box, typing 1.25 there
    sets it (the light-map setting follows), and Shift+wheel over the light shows in the box."""
    run = next(step for step in session[0] if step["run"] == "lights")
    added = run["added"]
    new = added["map"]["lights"][added["selected"]]
    assert len(added["map"]["lights"]) == 2 and new.get("angle") == SUN, added["map"]
    run = _run(session[0], "lights")  # the rest of the run went without an error
    initial, typed, wheeled = run["initial"], run["typed"], run["wheeled"]
    assert initial["intensity"] == preset("softbox").lights[0].intensity and initial["intensity_sensitive"]
    assert added["intensity"] == NEW_INTENSITY and added["label"] == "(custom)"
    assert typed["map"]["lights"][typed["selected"]]["intensity"] == 1.25 and typed["intensity"] == 1.25
    assert LightMap.from_json(run["typed_setting"]).lights[typed["selected"]].intensity == 1.25
    assert wheeled["map"]["lights"][wheeled["selected"]]["intensity"] == pytest.approx(1.35)
    assert wheeled["intensity"] == pytest.approx(1.35)


def test_the_dialog_fits_a_768_pixel_wide_screen_with_ok_on_it(narrow_session):
    """Issue item d: on a 768 x 1366 portrait screen the side-by-side dialog (about 800 pixels wide) put OK past
    the screen's right edge; there the preview goes under the light map, and the whole dialog, OK included, is on
    the screen, for a portrait and a landscape image."""
    for index in range(2):
        shown = _run(narrow_session[0], "layout", index)["shown"]
        print(f"\n768 x 1366: dialog {shown['size']}, OK at {shown['ok']}")
        assert shown["screen"] == list(NARROW_SCREEN), shown["screen"]
        left, top, right, bottom = shown["ok"]
        assert 0 <= left < right <= NARROW_SCREEN[0] and 0 <= top < bottom <= NARROW_SCREEN[1], shown["ok"]
        assert shown["size"][0] <= NARROW_SCREEN[0] and shown["size"][1] <= NARROW_SCREEN[1], shown["size"]
        assert shown["stacked"] and not shown["scrolled"], shown


def test_lift_and_thickness_are_set_kept_with_the_image_and_reset(session):
    """The issue's lift and thickness controls: a lift typed past 20 canvas heights is clamped to 4800 on the 240-row
    image and the note says why; dragging the ground point under the object in the preview sets the lift (canvas
    rows = preview rows / scale, less the row its lift counts from), live; the slider sets the thickness (From outline
    unticks, the value and the reading show); OK keeps both with the image (a parasite), the next dialog on it
    opens with them, Reset to Initial Values brings them back after a drag and Reset to Factory Defaults rests the
    object and reads its thickness; another image opens with neither."""
    run = _run(session[0], "geometry")
    initial, typed, dragged, slid = run["initial"], run["typed"], run["dragged"], run["slid"]
    print(f"\nlift and thickness: {initial}\n{typed}\n{dragged}\n{slid}")
    assert initial["lift"] == 0.0 and initial["thickness"] == -1.0 and initial["from_outline"]
    assert initial["read"] is not None and initial["value"] == f"read {initial['read']:.2f}", initial
    assert typed["lift"] == 4800.0, typed
    assert "more than 20 canvas heights (4800 px" in typed["note"], typed["note"]
    row, scale = dragged["lift_row"], dragged["scale"]
    assert dragged["bbox"][1] < row < dragged["bbox"][3], dragged  # the cutout's lowest pixel's row, within its box
    assert dragged["lift"] == round(run["dragged_to"] / scale) - row > 0, (dragged, run["dragged_to"])
    assert "canvas heights" not in dragged["note"], dragged["note"]  # the note is about the last change only
    assert slid["thickness"] == 1.0 and not slid["from_outline"] and slid["value"].startswith("1.00 (read ")
    width, height = slid["size"]
    assert height <= MAX_HEIGHT, slid["size"]
    runs = [outcome for outcome in session[1] if outcome["run"].startswith("geometry")]
    assert runs[0]["status"] == "success" and runs[0]["layers"] == ["Pawn", "Shadow: Pawn", "Background"], runs[0]
    kept = json.loads(runs[0]["geometry_record"])
    assert (kept["lift"], kept["thickness"], kept["height"]) == (dragged["lift"], 1.0, 240), kept
    again = _run(session[0], "geometry-again")
    assert (again["initial"]["lift"], again["initial"]["thickness"]) == (dragged["lift"], 1.0), again["initial"]
    assert again["dragged"]["lift"] != dragged["lift"], again["dragged"]
    after = again["after_initial"]
    assert (after["lift"], after["thickness"], after["from_outline"]) == (dragged["lift"], 1.0, False), after
    factory = again["after_factory"]
    assert (factory["lift"], factory["thickness"], factory["from_outline"]) == (0.0, -1.0, True), factory
    assert factory["value"] == f"read {factory['read']:.2f}", factory
    assert runs[1]["status"] == "cancel" and json.loads(runs[1]["geometry_record"]) == kept  # Cancel keeps it
    other = _run(session[0], "geometry-other")["initial"]
    assert (other["lift"], other["thickness"], other["from_outline"]) == (0.0, -1.0, True), other
    assert runs[2]["geometry_record"] is None
