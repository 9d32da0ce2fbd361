"""Real GIMP 3 integration test: the plug-in inside gimp-console-3.0 in a Debian 13 chroot.

The chroot (tools/gimp_chroot.sh, cached outside the checkout in
$SSN_GIMP_CHROOT, default /var/cache/ssn-shadow/gimp-trixie) is built once per
machine. The engine worker runs on the host (``ssn-shadow serve --port 0``);
the plug-in reaches it through the loopback socket, the chroot sharing the
host's network namespace. One gimp-console session runs every case of
gimp_batch_check.py (checked against the engine run directly on the same
cutout); a second one under Xvfb drives the dialog (gimp_dialog_check.py);
the GIMP GUI under Xvfb gets a real Ctrl+Z (gimp_undo_check.py).

Skips when the chroot is missing and cannot be built, unless CI=true (then it
fails instead).
"""

from __future__ import annotations

import json
import os
import re
import shutil
import subprocess
import sys
import tempfile
import time
import zipfile
from pathlib import Path

import numpy as np
import pytest

from loopback_worker import loopback_worker

from plugin_gimp.install import install
from ssn_engine.host_kit.client import EngineClient
from ssn_engine.host_kit.protocol import Buffer

pytestmark = pytest.mark.gimp

ROOT = Path(__file__).resolve().parents[2]
TOOL = ROOT / "tools" / "gimp_chroot.sh"
BATCH_SCRIPT = Path(__file__).with_name("gimp_batch_check.py")
DIALOG_SCRIPT = Path(__file__).with_name("gimp_dialog_check.py")
UNDO_SCRIPT = Path(__file__).with_name("gimp_undo_check.py")
SCENE_SCRIPT = Path(__file__).with_name("gimp_pawn_scene.py")
KIT_SCRIPT = Path(__file__).with_name("gimp_check_kit.py")  # what the check scripts share: they import it
RELAY_SCRIPT = Path(__file__).with_name("stdio_relay.py")
SETUP_SCRIPT = Path(__file__).with_name("gimp_setup_check.py")
SETUP_PRESS = Path(__file__).with_name("gimp_setup_press.py")
HOST_CERTIFICATES = Path("/etc/ssl/certs/ca-certificates.crt")  # this machine's trust (a proxy's CA included)
IN_CI = os.environ.get("CI") == "true"

W, H = 320, 240
PAWN = {"name": "Pawn", "x": 100, "y": 20, "w": 120, "h": 200, "rect": [40, 20, 80, 190]}
LEFT_LIGHT = json.dumps(
    {"format": "ssn-shadow-elm", "version": 1, "lights": [{"u": 0.3, "v": 0.75, "softness": 0.004, "intensity": 2.5}]}
)
HIGH_SUN = {"light-map": "high-sun", "opacity": 1.0, "ao-strength": 1.0, "shadow-color": [0, 0, 0]}
CASES = [
    # u8 perceptual RGB, cutout from the layer's alpha (layer offset on the canvas); light right -> shadow left
    {
        "id": "rgb-u8-nonlinear",
        "base": "RGB",
        "precision": "U8_NON_LINEAR",
        "cutout": PAWN,
        "args": {"light-map": "low-sun-right", "opacity": 1.0, "ao-strength": 1.0, "shadow-color": [0, 0, 0]},
        "side": "left",
    },
    # u16 linear RGB, ELM JSON with a light left of centre -> shadow right; colour, opacity, AO strength
    {
        "id": "rgb-u16-linear",
        "base": "RGB",
        "precision": "U16_LINEAR",
        "cutout": PAWN,
        "args": {"light-map": LEFT_LIGHT, "opacity": 0.7, "ao-strength": 0.5, "shadow-color": [0.2, 0.1, 0.4]},
        "side": "right",
    },
    # float linear grey
    {
        "id": "gray-float-linear",
        "base": "GRAY",
        "precision": "FLOAT_LINEAR",
        "cutout": PAWN,
        "args": {"light-map": "low-sun-right", "opacity": 0.9, "ao-strength": 2.0, "shadow-color": [0, 0, 0]},
        "side": "left",
    },
    # half perceptual RGB; the layer has no alpha, the cutout is an ellipse selection
    {
        "id": "rgb-half-perceptual-selection",
        "base": "RGB",
        "precision": "HALF_PERCEPTUAL",
        "cutout": {**PAWN, "alpha": False},
        "select": [140, 40, 40, 170],
        "args": {"light-map": "low-sun-left", "opacity": 1.0, "ao-strength": 1.0, "shadow-color": [0, 0, 0]},
        "side": "right",
    },
    # u16 perceptual grey from the layer alpha, the default preset
    {
        "id": "gray-u16-perceptual",
        "base": "GRAY",
        "precision": "U16_PERCEPTUAL",
        "cutout": PAWN,
        "args": {"light-map": "softbox", "opacity": 0.8, "ao-strength": 1.0, "shadow-color": [0, 0, 0]},
        "side": None,
    },
    # 32-bit integer and double precisions (the worker renders float32; babl converts)
    {
        "id": "rgb-u32-linear",
        "base": "RGB",
        "precision": "U32_LINEAR",
        "cutout": PAWN,
        "args": {"light-map": "low-sun-right", "opacity": 1.0, "ao-strength": 1.0, "shadow-color": [0, 0, 0]},
        "side": "left",
    },
    {
        "id": "gray-double-perceptual",
        "base": "GRAY",
        "precision": "DOUBLE_PERCEPTUAL",
        "cutout": PAWN,
        "args": {"light-map": LEFT_LIGHT, "opacity": 1.0, "ao-strength": 1.0, "shadow-color": [0, 0, 0]},
        "side": "right",
    },
    # a layer mask hides the right half of the pawn: only the visible half casts (issue #14, item 10)
    {
        "id": "rgb-u8-layer-mask",
        "base": "RGB",
        "precision": "U8_NON_LINEAR",
        "cutout": PAWN,
        "mask_right_half": True,
        "args": {"light-map": "softbox", "opacity": 1.0, "ao-strength": 1.0, "shadow-color": [0, 0, 0]},
        "side": None,
    },
    # the image's horizon (issue #14, horizon control): high above the canvas, a camera looking steeply down
    {
        "id": "rgb-u8-horizon",
        "base": "RGB",
        "precision": "U8_NON_LINEAR",
        "cutout": PAWN,
        "args": {
            "light-map": "low-sun-right",
            "opacity": 1.0,
            "ao-strength": 1.0,
            "shadow-color": [0, 0, 0],
            "use-horizon": True,
            "horizon": -300.0,
            "fov": 40.0,
        },
        "side": "left",
    },
    # the artist's geometry (lift and thickness arguments): the pawn floating 25 rows, and the same resting
    {
        "id": "rgb-u8-lift",
        "base": "RGB",
        "precision": "U8_NON_LINEAR",
        "cutout": PAWN,
        "args": {**HIGH_SUN, "lift": 25.0, "thickness": 0.5},
        "side": None,
    },
    {
        "id": "rgb-u8-lift-resting",
        "base": "RGB",
        "precision": "U8_NON_LINEAR",
        "cutout": PAWN,
        "args": {**HIGH_SUN, "lift": 0.0, "thickness": 0.5},
        "side": None,
    },
    # a lift past 20 canvas heights (4800 rows here), and one whose ground lies above the given horizon (row 230;
    # the pawn's foot is row 209)
    {
        "id": "error-lift-too-far",
        "base": "RGB",
        "precision": "U8_NON_LINEAR",
        "cutout": PAWN,
        "args": {**HIGH_SUN, "lift": 5000.0},
        "error": "lift: expected 0 to 4800 canvas pixels",
    },
    {
        "id": "error-lift-above-the-horizon",
        "base": "RGB",
        "precision": "U8_NON_LINEAR",
        "cutout": PAWN,
        "args": {**HIGH_SUN, "lift": 5.0, "use-horizon": True, "horizon": 230.0, "fov": 45.0},
        "error": "at or above the horizon (row 230)",
    },
    # errors: no selection and no alpha; a malformed light map
    {
        "id": "error-no-alpha",
        "base": "RGB",
        "precision": "U8_NON_LINEAR",
        "cutout": {**PAWN, "alpha": False},
        "args": {"light-map": "softbox"},
        "error": "selection is empty",
    },
    {
        "id": "error-bad-light-map",
        "base": "RGB",
        "precision": "U8_NON_LINEAR",
        "cutout": PAWN,
        "args": {
            "light-map": '{"format": "ssn-shadow-elm", "version": 1, "lights": [{"u": 1.5, "v": 0.2, '
            '"softness": 0.01, "intensity": 1}]}'
        },
        "error": "lights[0].u",
    },
    # issue #14: an indexed image (item 13), a locked group (11), opacity 0 and a 1-pixel selection (14)
    {
        "id": "error-indexed",
        "base": "RGB",
        "precision": "U8_NON_LINEAR",
        "cutout": PAWN,
        "indexed": True,
        "args": {"light-map": "softbox"},
        "error": "Image > Mode > RGB",
    },
    {
        "id": "error-locked-group",
        "base": "RGB",
        "precision": "U8_NON_LINEAR",
        "cutout": PAWN,
        "locked_group": True,
        "args": {"light-map": "softbox"},
        "error": "contents are locked",
    },
    {
        "id": "error-opacity-zero",
        "base": "RGB",
        "precision": "U8_NON_LINEAR",
        "cutout": PAWN,
        "args": {"light-map": "softbox", "opacity": 0.0},
        "error": "opacity is 0",
    },
    # running again on the shadow (Ctrl+F with the new shadow active) and on the source replaces the shadow
    {
        "id": "rgb-u8-rerun",
        "base": "RGB",
        "precision": "U8_NON_LINEAR",
        "cutout": PAWN,
        "args": {"light-map": "low-sun-right", "opacity": 1.0, "ao-strength": 1.0, "shadow-color": [0, 0, 0]},
        "reruns": ["shadow", "source"],
        "side": "left",
    },
    # a hidden layer and a layer at opacity 0 say so
    {
        "id": "error-hidden-layer",
        "base": "RGB",
        "precision": "U8_NON_LINEAR",
        "cutout": PAWN,
        "hidden": True,
        "args": {"light-map": "softbox"},
        "error": 'layer "Pawn" is hidden',
    },
    {
        "id": "error-layer-opacity-zero",
        "base": "RGB",
        "precision": "U8_NON_LINEAR",
        "cutout": PAWN,
        "layer_opacity": 0.0,
        "args": {"light-map": "softbox"},
        "error": 'layer "Pawn" is at opacity 0',
    },
    {
        "id": "error-one-pixel-selection",
        "base": "RGB",
        "precision": "U8_NON_LINEAR",
        "cutout": PAWN,
        "select": [160, 100, 1, 1],
        "args": {"light-map": "softbox"},
        "error": "too small to cast a visible shadow",
    },
]
for _case in CASES:
    _case.update(width=W, height=H)


def _chroot_dir() -> Path | None:
    """The ready chroot, building it if possible; None if it cannot be had."""
    status = subprocess.run([str(TOOL), "status"], capture_output=True, text=True)
    if status.returncode == 0 and os.geteuid() == 0:
        return Path(status.stdout.split(None, 1)[1].strip())
    if os.geteuid() != 0:  # chroot and mount need root, even for a ready chroot
        return None
    if shutil.which("debootstrap") is None:
        return None
    build = subprocess.run([str(TOOL), "build"], capture_output=True, text=True, timeout=1800)
    if build.returncode != 0:
        sys.stderr.write(build.stderr[-4000:])
        return None
    return Path(build.stdout.strip().splitlines()[-1])


@pytest.fixture(scope="module")
def chroot() -> Path:
    path = _chroot_dir()
    if path is None:
        if IN_CI:
            pytest.fail("CI=true: the GIMP 3 chroot could not be built (needs root, debootstrap and the network)")
        pytest.skip("no GIMP 3 chroot and it cannot be built here (needs root and debootstrap)")
    return path


@pytest.fixture(scope="module")
def worker():
    """A host engine worker on a loopback port: yields (port, token)."""
    with loopback_worker(ROOT) as port_token:
        yield port_token


@pytest.fixture(scope="module")
def workdir(chroot, worker):
    """A throwaway folder inside the chroot's /tmp with a GIMP profile holding the plug-in: (host path, inner path)."""
    port, token = worker
    work = Path(tempfile.mkdtemp(prefix="ssn-gimp-test-", dir=chroot / "tmp"))
    try:
        install(work / "profile" / "plug-ins" / "ssn-shadow", address=("127.0.0.1", port), token=token)
        (work / "out").mkdir()
        yield work, "/tmp/" + work.name  # the same folder seen from inside the chroot
    finally:
        shutil.rmtree(work, ignore_errors=True)


def run_gimp(
    inner: str, code: str, profile: str = "profile", timeout_s: float = 240, **env: str
) -> tuple[subprocess.CompletedProcess, float]:
    env = {**os.environ, "SSN_GIMP3_DIRECTORY": f"{inner}/{profile}", **env}
    start = time.monotonic()
    run = subprocess.run([str(TOOL), "gimp-eval", code], env=env, capture_output=True, text=True, timeout=timeout_s)
    return run, time.monotonic() - start


def run_check(inner: str, code: str, out: Path, session: str, **options: str) -> tuple:
    """Run ``code`` in GIMP (``options``: run_gimp's) and print how long the ``session`` took: (the JSON the check
    wrote to ``out``, a host path; GIMP's log). Fails, showing the log's end, where the check wrote nothing."""
    run, seconds = run_gimp(inner, code, **options)
    log = run.stdout + run.stderr
    print(f"\n{session}: {seconds:.1f} s")
    assert out.exists(), log[-6000:]
    return json.loads(out.read_text()), log


@pytest.fixture(scope="module")
def gimp_results(workdir):
    work, inner = workdir
    shutil.copy(BATCH_SCRIPT, work / "check.py")
    (work / "job.json").write_text(json.dumps({"out_dir": inner + "/out", "cases": CASES}))
    run, seconds = run_gimp(inner, f'JOB_PATH = "{inner}/job.json"; exec(open("{inner}/check.py").read())')
    log = run.stdout + run.stderr
    results_path = work / "out" / "results.json"
    assert results_path.exists(), f"GIMP wrote no results (rc {run.returncode}):\n{log[-6000:]}"
    results = {r["name"]: r for r in json.loads(results_path.read_text())}
    arrays = {}
    for name, r in results.items():
        for key in ("cutout_pixels", "shadow_pixels"):
            if key in r:
                arrays[(name, key)] = np.fromfile(work / "out" / Path(r[key]).name, dtype="<f4")
    runs = ", ".join(f"{r['name']} {r['seconds']:.2f} s" for r in results.values() if "seconds" in r)
    print(f"\ngimp-console session: {seconds:.1f} s for {len(CASES)} cases; procedure runs: {runs}")
    return results, arrays, log


def _expected(worker: tuple[int, str], case: dict, cutout: np.ndarray) -> tuple[dict, np.ndarray]:
    """What the engine renders for this cutout and these settings (as the plug-in would ask)."""
    u8 = case["precision"].startswith("U8")
    alpha = np.round(cutout * (255 if u8 else 65535)).astype("uint8" if u8 else "uint16").reshape(H, W)
    args = case["args"]
    client = EngineClient(address=("127.0.0.1", worker[0]), token=worker[1])
    try:
        camera = {"camera": {"horizon": args["horizon"], "fov": args["fov"]}} if args.get("use-horizon") else {}
        if "lift" in args or "thickness" in args:  # the artist's geometry; a thickness below 0 reads the outline
            thickness = args.get("thickness", -1.0)
            camera.update(lift=args.get("lift", 0.0), thickness=None if thickness < 0 else thickness)
        reply, _ = client.request(
            "set_cutout", {"alpha": Buffer(str(alpha.dtype), alpha.shape, alpha.tobytes())}, **camera
        )
        cid = reply["cutout"]
        if args["ao-strength"] != 1.0:
            client.request("edit_ao", cutout=cid, edits=[{"op": "strength", "value": args["ao-strength"]}])
        lm = args["light-map"]
        params = {"light_map": json.loads(lm)} if lm.startswith("{") else {"preset": lm}
        reply, buffers = client.request(
            "render",
            cutout=cid,
            color=list(args["shadow-color"]),
            opacity=args["opacity"],
            format={"dtype": "float32", "channels": "rgba"},
            margin=round(0.1 * max(W, H)),  # the plug-in's default: the canvas and a tenth of its larger side
            **params,
        )
        layer = np.frombuffer(buffers["layer"].data, "<f4").reshape(reply["height"], reply["width"], 4)
        return reply, layer
    finally:
        client.close()


def test_procedure_registered_and_cases_ran(gimp_results):
    results, _, log = gimp_results
    for case in CASES:
        r = results[case["id"]]
        assert "exception" not in r, r["exception"]
        assert r["registered"], log[-4000:]


@pytest.mark.parametrize("case", [c for c in CASES if "error" not in c], ids=lambda c: c["id"])
def test_shadow_layer(gimp_results, worker, case):
    results, arrays, log = gimp_results
    r = results[case["id"]]
    assert r["status"] == "success", r.get("error")
    # a new layer "Shadow: Pawn" directly below the drawable, returned by the procedure, in Multiply mode
    assert r["layers_after"] == ["Pawn", "Shadow: Pawn", "Background"]
    assert r["shadow_position"] == r["source_position"] + 1
    assert r["returned_layer"] == "Shadow: Pawn" and r["shadow_mode"] == "multiply"
    # the drawable and the selection untouched
    assert r["source_unchanged"] and r["source_offsets"] == [PAWN["x"], PAWN["y"]]
    assert r["selection_unchanged"]
    assert r["undo_enabled"]
    # the layer sits where the engine places the shadow of this cutout, with its pixels
    cutout = arrays[(case["id"], "cutout_pixels")]
    reply, want = _expected(worker, case, cutout)
    assert r["shadow_offsets"] == [reply["x"], reply["y"]]
    assert r["shadow_size"] == [reply["width"], reply["height"]]
    got = arrays[(case["id"], "shadow_pixels")].reshape(reply["height"], reply["width"], 4)
    step = 1 / 255 if case["precision"].startswith("U8") else 2e-3
    assert np.abs(got[..., 3] - want[..., 3]).max() <= step + 1e-4
    assert got[..., 3].max() > 0.3 * case["args"]["opacity"]
    # the colour (sRGB) where the shadow is visible; a grey image keeps the luminance only
    visible = got[..., 3] > 0.05
    colour = np.array(case["args"]["shadow-color"], "f4")
    if case["base"] == "RGB":
        assert np.abs(got[visible][:, :3] - colour).max() <= 2 * step
    # the geometry: a light right of centre casts the shadow left of the object, and vice versa
    if case["side"]:
        ys, xs = np.nonzero(got[..., 3] > 0.2)
        shadow_cx = reply["x"] + xs.mean()
        mask = cutout.reshape(H, W) > 0.5
        object_cx = np.nonzero(mask)[1].mean()
        assert (shadow_cx < object_cx - 10) if case["side"] == "left" else (shadow_cx > object_cx + 10)
    # the user's active layer stays active
    assert r["selected_after"] == ["Pawn"]


def test_a_low_sun_shadow_reaches_past_the_canvas_by_the_margin(gimp_results):
    """The low sun's shadow runs off the 320 x 240 canvas to the left: the GIMP layer goes a tenth of the canvas's
    larger side past its edge, no further (the whole shadow only when asked)."""
    r = gimp_results[0]["rgb-u8-nonlinear"]
    assert r["shadow_offsets"][0] == -32, r["shadow_offsets"]


def test_a_lift_moves_the_shadow_layer_down(gimp_results):
    """The lift argument (a batch call): the pawn floating 25 rows casts a shadow whose topmost row (alpha over
    0.2) lies lower on the canvas than the resting pawn's, under the same high sun and thickness."""
    results, arrays, _ = gimp_results
    tops = {}
    for name in ("rgb-u8-lift", "rgb-u8-lift-resting"):
        r = results[name]
        assert r["status"] == "success", r.get("error")
        width, height = r["shadow_size"]
        alpha = arrays[(name, "shadow_pixels")].reshape(height, width, 4)[..., 3]
        tops[name] = r["shadow_offsets"][1] + int(np.nonzero((alpha > 0.2).any(axis=1))[0][0])
    print(f"\ntopmost shadow row: lifted 25 rows {tops['rgb-u8-lift']}, resting {tops['rgb-u8-lift-resting']}")
    assert tops["rgb-u8-lift"] > tops["rgb-u8-lift-resting"] + 10, tops


def test_running_again_replaces_the_shadow(gimp_results):
    """Run on the new shadow (what Ctrl+F does next) and then on the source: each re-casts the source's shadow in
    place, never "Shadow: Shadow: Pawn" nor a second "Shadow: Pawn"; the active layer stays what it was."""
    reruns = gimp_results[0]["rgb-u8-rerun"]["reruns"]
    assert [r["status"] for r in reruns] == ["success", "success"]
    for r in reruns:
        assert r["layers"] == ["Pawn", "Shadow: Pawn", "Background"] and r["returned"] == "Shadow: Pawn"
    assert reruns[0]["returned_is_selected"]  # run on the shadow: the new shadow is the active layer
    assert reruns[1]["selected"] == ["Pawn"]  # run on the source: the source stays active


@pytest.mark.parametrize("case", [c for c in CASES if "error" in c], ids=lambda c: c["id"])
def test_errors_are_clear_and_change_nothing(gimp_results, case):
    results, _, _ = gimp_results
    r = results[case["id"]]
    assert r["status"] == "execution-error", repr({k: v for k, v in r.items() if not k.endswith("_pixels")})
    assert case["error"] in r["error"] and "unexpectedly" not in r["error"], r["error"]
    assert r["layers_after"] == r["layers_before"]
    assert r["source_unchanged"] and r["selection_unchanged"]


def test_undo_group_closed(gimp_results):
    """The plug-in left no undo group open (GIMP core warns when a plug-in does) and nothing crashed."""
    _, _, log = gimp_results
    assert "inconsistent" not in log.lower(), log[-4000:]
    assert "plug-in crashed" not in log.lower() and "traceback" not in log.lower(), log[-4000:]


def kit_on_path(work: Path, inner: str) -> str:
    """Copy the check scripts' shared kit into ``work`` (``inner`` inside the chroot); python-fu-eval code that puts
    it where they import it from."""
    shutil.copy(KIT_SCRIPT, work / KIT_SCRIPT.name)
    return f'import sys; sys.path.insert(0, "{inner}"); '


def _exec_scene_then(work: Path, inner: str, script: str, precision: str = "") -> str:
    """python-fu-eval code: build the shared pawn scene (at ``precision``, a Gimp.Precision name, if given), then
    run ``script`` (in ``work``, ``inner`` inside the chroot) in the same globals; copies the scene and the kit."""
    shutil.copy(SCENE_SCRIPT, work / "scene.py")
    return kit_on_path(work, inner) + (
        f'SCENE_PRECISION = "{precision}"; exec(open("{inner}/scene.py").read()); exec(open("{inner}/{script}").read())'
    )


def test_one_undo_removes_the_shadow(workdir):
    """GIMP 3's PDB has no undo command, so the GUI (gimp-3.0 under Xvfb) gets a real Ctrl+Z (xdotool)."""
    work, inner = workdir
    shutil.copy(UNDO_SCRIPT, work / "undo.py")
    code = f'OUT_PATH = "{inner}/out/undo.json"; {_exec_scene_then(work, inner, "undo.py")}'
    result, log = run_check(inner, code, work / "out" / "undo.json", "gimp-3.0 GUI undo session", SSN_GIMP_GUI="1")
    assert result["status"] == "success"
    assert result["after"] == ["Pawn", "Shadow: Pawn", "Background"]
    assert result["window"], f"no image window found: {result}\n{log[-3000:]}"
    assert result["after_undo"] == result["before"] == ["Pawn", "Background"], result


@pytest.mark.parametrize("precision", ["", "U16_LINEAR", "DOUBLE_PERCEPTUAL"])
def test_interactive_dialog(workdir, worker, precision):
    """The dialog under Xvfb: built, light map edited, preview rendered, OK pressed (the plug-in's
    SSN_SHADOW_DIALOG_SELFTEST hook), and the shadow layer made from the edited light map; at 8 bits and at
    precisions where GIMP makes no thumbnail (issue #14, item 9: the dialog crashed there). Each run has a
    fresh GIMP profile: GIMP remembers the last light map, which would change where the self-test's press
    lands."""
    work, inner = workdir
    profile = f"profile-dialog{precision}"
    install(work / profile / "plug-ins" / "ssn-shadow", address=("127.0.0.1", worker[0]), token=worker[1])
    (work / "out" / "dialog.json").unlink(missing_ok=True)
    shutil.copy(DIALOG_SCRIPT, work / "dialog.py")
    env = {"SSN_GIMP_XVFB": "1", "SSN_SHADOW_DIALOG_SELFTEST": "1"}
    if os.environ.get("SSN_GIMP_DIALOG_SCREENSHOT"):
        env["SSN_SHADOW_DIALOG_SCREENSHOT"] = inner + "/out/dialog.png"
    code = f'OUT_PATH = "{inner}/out/dialog.json"; {_exec_scene_then(work, inner, "dialog.py", precision)}'
    result, log = run_check(
        inner, code, work / "out" / "dialog.json", "gimp-console dialog session", profile=profile, **env
    )
    assert result["status"] == "success", result.get("error")
    assert result["layers"] == ["Pawn", "Shadow: Pawn", "Background"]
    line = next((ln for ln in log.splitlines() if ln.startswith("ssn-shadow dialog selftest: lights=")), None)
    assert line is not None, log[-6000:]
    assert "lights=2" in line and "preview=200x150" in line
    # no horizon set: the preview says which camera the model read, and the horizon option starts from it
    read = re.search(
        r"Camera read from the cutout's outline: horizon at row (-?\d+) \((?:dotted blue|above the image|below the "
        r"image)\), (\d+)° field of view",
        line,
    )
    assert read is not None, line
    assert f"horizon setting {read[1]}, field of view {read[2]}, on: False" in log, log[-3000:]
    # the light added by a press at (0.85, 0.7) of the map and dragged by (-0.05, +0.02) through the widget
    assert "ssn-shadow dialog selftest: light at u=0.800 v=0.720" in log, log[-3000:]
    # the Size box sets the light's size in degrees: 0.53 exactly, and its shadow is crisper than at 30
    size = re.search(
        r"size box (\S+), light angle (\S+), shadow crispness at 30 degrees (\S+), at 0.53 degrees (\S+)", log
    )
    assert size is not None, log[-3000:]
    assert size[1] == "0.53" and size[2] == "0.53", size[0]
    assert float(size[4]) > 2.0 * float(size[3]), size[0]  # 12 degrees, now traced, was nearly as crisp
    # Reset to Factory Defaults / Load Saved Settings reach the light map (issue #14, item 12)
    assert "after a settings reset the map shows high-sun: True" in log, log[-3000:]
    # the light map and the preview side by side: the dialog fits a 1366 x 768 screen with a title bar and a
    # panel (stacked, it was 814 px tall and its OK button was off-screen)
    size = re.search(r"ssn-shadow dialog selftest: dialog (\d+)x(\d+)", log)
    assert size is not None, log[-3000:]
    assert int(size[1]) <= 1366 and int(size[2]) <= 700, size[0]
    assert "traceback" not in log.lower(), log[-6000:]
    if os.environ.get("SSN_GIMP_DIALOG_SCREENSHOT"):
        shutil.copy(work / "out" / "dialog.png", os.environ["SSN_GIMP_DIALOG_SCREENSHOT"])


def test_spawned_worker(workdir, worker):
    """The default engine.json (a command the plug-in spawns, talking over its stdin/stdout), in real GIMP.

    The chroot has no ssn-shadow, so the command is a stdlib relay to the host worker: the plug-in's
    own subprocess path runs, and the worker is the real one."""
    work, inner = workdir
    port, token = worker
    dest = install(work / "profile-spawn" / "plug-ins" / "ssn-shadow", python="/usr/bin/python3")
    shutil.copy(RELAY_SCRIPT, work / "relay.py")
    config = json.loads((dest / "engine.json").read_text())
    config["args"] = [inner + "/relay.py", "127.0.0.1", str(port), token]
    config["shared"] = False  # the relay speaks stdio only: this test is about the spawn path
    (dest / "engine.json").write_text(json.dumps(config))
    out = work / "out-spawn"
    out.mkdir()
    case = next(c for c in CASES if c["id"] == "rgb-u8-nonlinear")
    shutil.copy(BATCH_SCRIPT, work / "check.py")
    (work / "job-spawn.json").write_text(json.dumps({"out_dir": inner + "/out-spawn", "cases": [case]}))
    code = f'JOB_PATH = "{inner}/job-spawn.json"; exec(open("{inner}/check.py").read())'
    (result,), _ = run_check(
        inner, code, out / "results.json", "gimp-console spawned-worker session", profile="profile-spawn"
    )
    assert result["status"] == "success", result.get("error")
    assert result["layers_after"] == ["Pawn", "Shadow: Pawn", "Background"]
    assert result["source_unchanged"] and result["selection_unchanged"]


def unpack(archive: Path, dest: Path) -> None:
    """Unpack a zip as an artist's unzip does: with the modes it records (GIMP runs only an executable script)."""
    with zipfile.ZipFile(archive) as zf:
        for info in zf.infolist():
            path = Path(zf.extract(info, dest))
            mode = (info.external_attr >> 16) & 0o777
            if mode and not info.is_dir():
                path.chmod(mode)


def test_the_gimp_package_sets_up_its_engine_inside_gimps_system(chroot):
    """The one-file GIMP package unpacked into a fresh profile of the Debian 13 system GIMP runs in, where nothing
    of ssn-shadow is installed and Python has no ensurepip: a batch call says how to set up; the interactive one
    offers Set up, which makes the engine's environment there (pip fetched from the index), and the shadow follows
    from that engine."""
    from plugin_gimp import install as gimp_install
    from ssn_engine.plugin_package import package

    work = Path(tempfile.mkdtemp(prefix="ssn-gimp-setup-", dir=chroot / "tmp"))
    inner = "/tmp/" + work.name
    try:
        unpack(package(gimp_install, work / "ssn-shadow-gimp.zip"), work / "profile-setup" / "plug-ins")
        (work / "out").mkdir()
        env = {
            "SSN_GIMP_XVFB": "1",
            "SSN_SHADOW_DIALOG_SELFTEST": "1",
            "SSN_SHADOW_SETUP_TEST": inner + "/press.py",
            "SSN_SHADOW_DATA": inner + "/data",
        }
        if HOST_CERTIFICATES.is_file():  # the machine's network as this machine trusts it
            shutil.copy(HOST_CERTIFICATES, work / "certificates.crt")
            env.update(SSL_CERT_FILE=inner + "/certificates.crt", PIP_CERT=inner + "/certificates.crt")
        shutil.copy(SETUP_SCRIPT, work / "setup.py")
        shutil.copy(SETUP_PRESS, work / "press.py")
        if os.environ.get("SSN_GIMP_SETUP_SCREENSHOT"):  # a picture of the dialog while it installs, for the docs
            (work / "shot.txt").write_text(inner + "/out/setup.png")
        code = f'OUT_PATH = "{inner}/out/setup.json"; {_exec_scene_then(work, inner, "setup.py")}'
        run, seconds = run_gimp(inner, code, profile="profile-setup", timeout_s=1200, **env)
        log = run.stdout + run.stderr
        print(f"\ngimp set-up session: {seconds:.1f} s")
        assert (work / "out" / "setup.json").exists(), log[-6000:]
        result = json.loads((work / "out" / "setup.json").read_text())
        batch = result["batch"]
        assert batch["status"] == "execution-error" and batch["layers"] == ["Pawn", "Background"], batch
        assert "not set up yet" in batch["error"], batch
        assert "Open Filters > Light and Shadow > Soft Shadow (SSN)... once and press Set up." in batch["error"]
        assert "ssn-shadow set-up dialog: offered '_Set up'" in log, log[-6000:]
        assert re.search(r"set-up dialog: 0\.\d\d Installing the engine", log), log[-6000:]
        assert result["status"] == "success", (result.get("error"), log[-6000:])
        assert result["layers"] == ["Pawn", "Shadow: Pawn", "Background"]
        setup_log = (work / "data" / "setup.log").read_text()
        # no ensurepip there: the environment made without pip, and pip's wheel fetched from the index
        assert "--without-pip" in setup_log and "/pip install --no-index" in setup_log
        assert setup_log.rstrip().endswith("done"), setup_log[-3000:]
        assert (work / "data" / "engine" / "bin" / "python").exists()
        if os.environ.get("SSN_GIMP_SETUP_SCREENSHOT"):
            shutil.copy(work / "out" / "setup.png", os.environ["SSN_GIMP_SETUP_SCREENSHOT"])
    finally:
        shutil.rmtree(work, ignore_errors=True)
