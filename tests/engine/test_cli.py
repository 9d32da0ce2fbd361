"""The ssn-shadow command line (ssn_engine.cli)."""

from __future__ import annotations

import json
import re
import shutil
import subprocess
import sys

import numpy as np
import pytest
from engine_helpers import REPO, drawn_alpha, engine_env
from PIL import Image

from ssn_engine.cli import build_parser, main
from ssn_engine.host_kit.light_map import PRESETS, LightMap


def run_cli(*args, timeout=300):
    env = engine_env()
    return subprocess.run(
        [sys.executable, "-m", "ssn_engine", *args], capture_output=True, text=True, timeout=timeout, env=env
    )


W, H = 240, 180


@pytest.fixture
def cutout_png(tmp_path):
    """A small RGBA cutout: the drawn post, orange, on a transparent 240 x 180 canvas."""
    alpha = np.zeros((H, W), np.uint8)
    alpha[40:160, 40:200] = drawn_alpha(160, 120)
    rgba = np.zeros((H, W, 4), np.uint8)
    rgba[..., :3] = (220, 120, 40)
    rgba[..., 3] = alpha
    path = tmp_path / "cutout.png"
    Image.fromarray(rgba, "RGBA").save(path)
    return path


def _read(path):
    return np.asarray(Image.open(path))


def test_demo_writes_a_shaded_composite(tmp_path):
    from engine_helpers import pawn

    from ssn_engine.samples import SAMPLE_SIZE, studio_background

    out = tmp_path / "demo.png"
    result = run_cli("demo", "--out", str(out))
    assert result.returncode == 0, result.stderr
    assert f"wrote {out}" in result.stdout and "method:" in result.stdout
    image = _read(out)
    assert (image.shape[1], image.shape[0]) == SAMPLE_SIZE
    bg = studio_background().astype(int)
    alpha = pawn()[..., 3]
    ys, xs = np.nonzero(alpha > 127)
    base, x0, x1 = ys.max(), xs.min(), xs.max()
    below = (slice(base + 3, base + 25), slice(x0 + 20, x1 - 20))  # the ground just below the pawn
    assert image[below][..., :3].astype(int).mean() < bg[below].mean() - 20
    far = (slice(0, 60), slice(0, 60))  # a corner of the wall: untouched
    assert np.array_equal(image[far][..., :3], bg[far].astype(np.uint8))
    opaque = alpha == 255
    assert np.array_equal(image[opaque][:, :3], pawn()[opaque][:, :3])  # the cutout itself is unchanged


def test_render_layer_and_composite(tmp_path, cutout_png, capsys):
    layer, comp = tmp_path / "layer.png", tmp_path / "comp.png"
    code = main(
        [
            "render",
            str(cutout_png),
            "--layer",
            str(layer),
            "--composite",
            str(comp),
            "--color",
            "#203040",
            "--opacity",
            "0.5",
            "--preset",
            "low-sun-right",
        ]
    )
    assert code == 0
    out = capsys.readouterr().out
    assert f"wrote {layer}" in out and f"wrote {comp}" in out and "method:" in out
    lay = _read(layer)
    assert lay.shape == (H, W, 4)
    assert lay[..., 3].max() > 60 and lay[..., 3].max() <= 128  # opacity 0.5
    assert np.all(lay[lay[..., 3] > 0][:, :3] == (0x20, 0x30, 0x40))
    # low-sun-right: the light is right of centre, so the shadow falls left of the object
    ground = lay[..., 3].astype(float) * (_read(cutout_png)[..., 3] == 0)
    xx = np.arange(W)[None, :]
    assert (ground * xx).sum() / ground.sum() < 120 - 10
    c = _read(comp)
    assert c.shape[:2] == (H, W)
    assert np.all(c[0, 0, :3] == 255)  # default white background
    cut = _read(cutout_png)
    opaque = cut[..., 3] == 255
    assert np.array_equal(c[opaque][:, :3], cut[opaque][:, :3])
    shaded = ground > 40
    assert c[shaded][:, :3].mean() < 230


def test_render_over_a_background_with_a_light_map(tmp_path, cutout_png):
    bg = np.full((H, W, 3), 180, np.uint8)
    bg_path, elm_path, comp = tmp_path / "bg.png", tmp_path / "elm.json", tmp_path / "comp.png"
    Image.fromarray(bg).save(bg_path)
    lm = LightMap()
    lm.add(0.5, 0.75, 0.002, 3.0)  # straight ahead: shadow towards the viewer
    elm_path.write_text(lm.to_json())
    assert (
        main(
            [
                "render",
                str(cutout_png),
                "--composite",
                str(comp),
                "--background",
                str(bg_path),
                "--light-map",
                str(elm_path),
                "--opacity",
                "1",
            ]
        )
        == 0
    )
    c = _read(comp)[..., :3].astype(int)
    assert c[165:178, 100:140].mean() < 150  # below the object's base (row 160): darker
    assert np.all(c[:30] == 180)  # above the object: the background as it was


def test_ao_strength_changes_the_contact_shadow(tmp_path, cutout_png):
    a, b = tmp_path / "a.png", tmp_path / "b.png"
    assert main(["render", str(cutout_png), "--layer", str(a), "--preset", "overcast"]) == 0
    assert main(["render", str(cutout_png), "--layer", str(b), "--preset", "overcast", "--ao-strength", "0"]) == 0
    la, lb = _read(a)[..., 3].astype(int), _read(b)[..., 3].astype(int)
    assert lb.sum() < 0.9 * la.sum()  # AO strength 0 removes the contact occlusion: clearly less shadow
    # and almost nowhere more: the network's faint haze over the frame may rise by a few levels
    assert np.mean(lb > la + 4) < 0.02


def _error(capsys, *args):
    code = main(list(args))
    return code, capsys.readouterr().err


def test_missing_file(tmp_path, capsys):
    code, err = _error(capsys, "render", str(tmp_path / "nope.png"), "--layer", str(tmp_path / "l.png"))
    assert code == 2 and "nope.png" in err and "no such file" in err


def test_corrupt_png(tmp_path, capsys):
    bad = tmp_path / "bad.png"
    bad.write_bytes(b"\x89PNG\r\n\x1a\n" + bytes(range(200)))
    code, err = _error(capsys, "render", str(bad), "--layer", str(tmp_path / "l.png"))
    assert code == 2 and "bad.png" in err and "not a readable image" in err


def test_fully_transparent_cutout_and_a_light_map_without_light(cutout_png, tmp_path, capsys):
    """Nothing casts, or nothing lights: the same "no visible shadow" answer (exit 3), and nothing written."""
    empty = tmp_path / "empty.png"
    Image.fromarray(np.zeros((20, 30, 4), np.uint8), "RGBA").save(empty)
    code, err = _error(capsys, "render", str(empty), "--layer", str(tmp_path / "l.png"))
    assert code == 3 and "no visible shadow" in err and "fully transparent" in err
    dark = tmp_path / "dark.json"
    for lights in ([], [{"u": 0.3, "v": 0.5, "softness": 0.01, "intensity": 0.0}]):
        dark.write_text(json.dumps({"format": "ssn-shadow-elm", "version": 1, "lights": lights}))
        code, err = _error(
            capsys, "render", str(cutout_png), "--layer", str(tmp_path / "l.png"), "--light-map", str(dark)
        )
        assert code == 3 and "no visible shadow" in err and "no light" in err
    assert not (tmp_path / "l.png").exists()


def test_unknown_preset_is_a_usage_error(cutout_png, tmp_path, capsys):
    with pytest.raises(SystemExit) as info:
        main(["render", str(cutout_png), "--layer", str(tmp_path / "l.png"), "--preset", "sunset-glow"])
    assert info.value.code == 2
    err = capsys.readouterr().err
    assert "sunset-glow" in err and "softbox" in err


@pytest.mark.parametrize(
    "text, fragment",
    [
        ("{broken", "not valid JSON"),
        (
            json.dumps(
                {
                    "format": "ssn-shadow-elm",
                    "version": 1,
                    "lights": [{"u": 2, "v": 0.5, "softness": 0.01, "intensity": 1}],
                }
            ),
            "lights[0].u",
        ),
    ],
)
def test_malformed_light_map(cutout_png, tmp_path, capsys, text, fragment):
    elm = tmp_path / "elm.json"
    elm.write_text(text)
    code, err = _error(capsys, "render", str(cutout_png), "--layer", str(tmp_path / "l.png"), "--light-map", str(elm))
    assert code == 2 and f"error: {elm}: " in err and fragment in err  # the message names the file


def test_missing_light_map_file(cutout_png, tmp_path, capsys):
    code, err = _error(
        capsys, "render", str(cutout_png), "--layer", str(tmp_path / "l.png"), "--light-map", str(tmp_path / "x.json")
    )
    assert code == 2 and "x.json" in err


def test_background_size_mismatch(cutout_png, tmp_path, capsys):
    bg = tmp_path / "bg.png"
    Image.fromarray(np.zeros((10, 10, 3), np.uint8)).save(bg)
    code, err = _error(
        capsys,
        "render",
        str(cutout_png),
        "--layer",
        str(tmp_path / "l.png"),
        "--composite",
        str(tmp_path / "c.png"),
        "--background",
        str(bg),
    )
    assert code == 2 and "10 x 10" in err and f"{W} x {H}" in err
    assert not (tmp_path / "c.png").exists() and not (tmp_path / "l.png").exists()  # checked before any write


def test_nothing_to_write(cutout_png, capsys):
    code, err = _error(capsys, "render", str(cutout_png))
    assert code == 2 and "--layer" in err


def test_horizon_and_fov_reach_the_method(tmp_path, cutout_png):
    """The image's horizon: seen from above (horizon far above the canvas), a shadow cast away from the viewer
    climbs further up the canvas than seen from a level camera (horizon at the cutout's foot)."""
    tops = []
    for horizon in ("150", "-600"):
        out = tmp_path / f"h{horizon}.png"
        argv = [
            "render",
            str(cutout_png),
            "--layer",
            str(out),
            "--method",
            "geometric",
            "--horizon",
            horizon,
            "--fov",
            "40",
            "--light-map",
            str(_light_file(tmp_path, 0.0, 0.75)),
        ]
        assert main(argv) == 0
        alpha = _read(out)[..., 3]
        tops.append(int(np.flatnonzero((alpha > 40).any(axis=1)).min()))
    assert tops[1] < tops[0] - 3


def test_a_blind_render_says_which_camera_it_read(tmp_path, cutout_png, capsys):
    """Without --horizon the shipped model reads the camera from the outline and prints it as the flags that set
    it; given those flags it has nothing to read."""
    import re

    layer = tmp_path / "layer.png"
    assert main(["render", str(cutout_png), "--layer", str(layer), "--method", "ssn"]) == 0
    read = re.search(r"camera read from the cutout's outline: (--horizon -?\d+ --fov \d+)", capsys.readouterr().out)
    assert read, "no camera reported"
    assert main(["render", str(cutout_png), "--layer", str(layer), "--method", "ssn", *read.group(1).split()]) == 0
    assert "camera read" not in capsys.readouterr().out


def _light_file(tmp_path, u, v):
    path = tmp_path / f"light_{u}_{v}.json"
    path.write_text(
        json.dumps(
            {
                "format": "ssn-shadow-elm",
                "version": 1,
                "lights": [{"u": u, "v": v, "softness": 0.002, "intensity": 1.0}],
            }
        )
    )
    return path


def test_fov_without_horizon_is_refused(cutout_png, tmp_path, capsys):
    code, err = _error(capsys, "render", str(cutout_png), "--layer", str(tmp_path / "l.png"), "--fov", "40")
    assert code == 2 and "horizon" in err and not (tmp_path / "l.png").exists()


@pytest.mark.parametrize(
    "args", [["--color", "red"], ["--opacity", "1.5"], ["--opacity", "x"], ["--fov", "0"], ["--horizon", "low"]]
)
def test_bad_option_values(cutout_png, tmp_path, capsys, args):
    with pytest.raises(SystemExit) as info:
        main(["render", str(cutout_png), "--layer", str(tmp_path / "l.png"), *args])
    assert info.value.code == 2
    assert args[0] in capsys.readouterr().err


def test_presets_lists_all_and_prints_json(capsys):
    assert main(["presets"]) == 0
    listing = capsys.readouterr().out
    for name in PRESETS:
        assert re.search(rf"^{re.escape(name)}\s+\d+ lights?$", listing, re.M)
    for name in PRESETS:
        assert main(["presets", name]) == 0
        text = capsys.readouterr().out
        assert LightMap.from_json(text).to_dict() == json.loads(text)
        assert json.loads(text)["format"] == "ssn-shadow-elm"
    code, err = _error(capsys, "presets", "sunset-glow")
    assert code == 2 and "sunset-glow" in err


def test_subprocess_exit_code_and_message():
    result = run_cli("render", "/nonexistent/cutout.png", "--layer", "/tmp/x.png")
    assert result.returncode == 2
    assert result.stderr.startswith("ssn-shadow: error:") and "no such file" in result.stderr
    assert "Traceback" not in result.stderr


def test_benchmark_prints_the_stage_table():
    """Each stage's median and p95, and where the project sets a budget, the budget and the median's ratio to it;
    then the peak memory against its budget and a verdict naming any stage over budget."""
    result = run_cli("benchmark", "--repeats", "2")
    assert result.returncode == 0, result.stderr
    lines = result.stdout.splitlines()
    header = next(i for i, line in enumerate(lines) if line.startswith("stage"))
    assert lines[header].split() == ["stage", "median", "ms", "p95", "ms", "budget", "ms", "ratio"]
    rows = lines[header + 1 : header + 11]
    budgets = {"AOP": 30, "AOP, camera given": 30, "SR": 15, "SR, sun dragged": 15, "geometric card": None}
    budgets["end to end 4000x3000"] = None
    budgets["light moved 4000x3000"] = 25
    budgets["tracer analysis 4000x3000"] = 30
    budgets["sun moved 4000x3000"] = 40
    budgets["lift changed 4000x3000"] = 40
    assert len(rows) == len(budgets)
    over = []
    for (name, budget), row in zip(budgets.items(), rows, strict=True):
        assert row.startswith(name), row
        median, p95, shown, ratio = row.split()[-4:]
        assert 0 < float(median) <= float(p95)
        if budget is None:
            assert (shown, ratio) == ("-", "-")
        else:
            assert float(shown) == budget and float(ratio) == pytest.approx(float(median) / budget, abs=0.01)
            over += [name] if float(median) > budget else []
    peak = next(line for line in lines if line.startswith("peak resident memory:"))
    assert "of the budget, 400 MiB" in peak
    over += ["peak memory"] if int(peak.split()[3]) > 400 else []
    verdict = lines[-1]  # agrees with the table as printed, also at a median of exactly the budget
    assert verdict.startswith("over budget: ") if over else verdict.startswith("within budget")
    assert all(name in verdict for name in over) and len(re.findall(r"\(\d+\.\d\d\)", verdict)) == len(over)


def test_the_demos_default_output_is_ignored_by_git():
    """`ssn-shadow demo` run in a checkout (as the README says) leaves no untracked file behind."""
    if shutil.which("git") is None or not (REPO / ".git").exists():
        pytest.skip("not a git checkout")
    default = build_parser().parse_args(["demo"]).out
    result = subprocess.run(["git", "check-ignore", "-q", default], cwd=REPO, capture_output=True, timeout=60)
    assert result.returncode == 0, f"{default} is not git-ignored ({result.stderr!r})"
