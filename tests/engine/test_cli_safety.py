"""ssn-shadow render and demo never cost the user a file: inputs are never overwritten, every check runs before
any work, writes are atomic, and large or odd images get a clear message."""

from __future__ import annotations

import errno
import os
import signal
import subprocess
import sys
import time
import warnings
from pathlib import Path

import numpy as np
import pytest
from engine_helpers import drawn_alpha, engine_env
from PIL import Image

from ssn_engine import cli
from ssn_engine.cli import main

W, H = 240, 180


@pytest.fixture
def cutout_png(tmp_path):
    rgba = np.zeros((H, W, 4), np.uint8)
    rgba[..., :3] = (220, 120, 40)
    rgba[40:160, 40:200, 3] = drawn_alpha(160, 120)
    path = tmp_path / "cutout.png"
    Image.fromarray(rgba, "RGBA").save(path)
    return path


def _run(capsys, *args):
    code = main([str(a) for a in args])
    out = capsys.readouterr()
    return code, out.out, out.err


def _files(folder):
    return sorted(p.name for p in folder.iterdir())


@pytest.mark.parametrize("alias", ["same", "relative", "hardlink", "symlink"])
def test_an_output_never_overwrites_the_cutout(cutout_png, tmp_path, capsys, monkeypatch, alias):
    before = cutout_png.read_bytes()
    target = {
        "same": cutout_png,
        "relative": "cutout.png",
        "hardlink": tmp_path / "hard.png",
        "symlink": tmp_path / "sym.png",
    }[alias]
    if alias == "hardlink":
        os.link(cutout_png, target)
    if alias == "symlink":
        os.symlink(cutout_png, target)
    monkeypatch.chdir(tmp_path)
    for flag in ("--layer", "--composite"):
        code, _, err = _run(capsys, "render", cutout_png, flag, target)
        assert code == 2 and "never writes over its inputs" in err and flag in err
    assert cutout_png.read_bytes() == before


def test_outputs_must_differ_from_the_background_and_each_other(cutout_png, tmp_path, capsys):
    bg = tmp_path / "bg.png"
    Image.fromarray(np.full((H, W, 3), 200, np.uint8)).save(bg)
    bg_bytes = bg.read_bytes()
    code, _, err = _run(capsys, "render", cutout_png, "--composite", bg, "--background", bg)
    assert code == 2 and "--background" in err and bg.read_bytes() == bg_bytes
    code, _, err = _run(capsys, "render", cutout_png, "--layer", tmp_path / "x.png", "--composite", tmp_path / "x.png")
    assert code == 2 and "name the same file" in err and not (tmp_path / "x.png").exists()


def test_every_check_runs_before_any_write(cutout_png, tmp_path, capsys):
    """A composite into a missing folder: refused up front, so no --layer file is left behind."""
    code, _, err = _run(
        capsys, "render", cutout_png, "--layer", tmp_path / "l.png", "--composite", tmp_path / "missing" / "c.png"
    )
    assert code == 2 and "does not exist" in err
    code, _, err = _run(capsys, "render", cutout_png, "--layer", tmp_path)
    assert code == 2 and "is a folder" in err
    assert _files(tmp_path) == ["cutout.png"]


def test_a_failed_write_leaves_no_partial_file_and_the_old_file_intact(cutout_png, tmp_path, capsys, monkeypatch):
    """The disk fills up while the composite is written: the old files at both paths are untouched (the layer,
    already written, is not put in place either) and no temporary file is left."""
    layer, composite = tmp_path / "l.png", tmp_path / "c.png"
    layer.write_bytes(b"old layer")
    composite.write_bytes(b"old composite")
    real_save = Image.Image.save
    calls = []

    def save(self, fp, *args, **kwargs):
        calls.append(fp)
        if len(calls) == 2:
            fp.write(b"\x89PNG half")
            raise OSError(errno.ENOSPC, "No space left on device")
        return real_save(self, fp, *args, **kwargs)

    monkeypatch.setattr(Image.Image, "save", save)
    code, _, err = _run(capsys, "render", cutout_png, "--layer", layer, "--composite", composite)
    assert code == 2 and "No space left" in err and str(composite) in err
    assert layer.read_bytes() == b"old layer" and composite.read_bytes() == b"old composite"
    assert _files(tmp_path) == ["c.png", "cutout.png", "l.png"]


def test_outputs_are_complete_pngs_with_the_usual_mode(cutout_png, tmp_path, capsys):
    code, out, _ = _run(capsys, "render", cutout_png, "--layer", tmp_path / "l.png")
    assert code == 0 and f"wrote {tmp_path / 'l.png'}" in out
    assert Image.open(tmp_path / "l.png").size == (W, H)
    mask = os.umask(0)
    os.umask(mask)
    assert (tmp_path / "l.png").stat().st_mode & 0o777 == 0o666 & ~mask


@pytest.mark.parametrize("kind", ["rgb-png", "jpeg", "opaque-rgba"])
def test_an_image_that_is_not_a_cutout_is_refused_unless_whole_image(tmp_path, capsys, kind):
    rgb = np.random.default_rng(0).integers(0, 255, (H, W, 3), dtype=np.uint8)
    path = tmp_path / ("photo.jpg" if kind == "jpeg" else "photo.png")
    if kind == "opaque-rgba":
        Image.fromarray(np.dstack([rgb, np.full((H, W), 255, np.uint8)]), "RGBA").save(path)
    else:
        Image.fromarray(rgb).save(path)
    code, _, err = _run(capsys, "render", path, "--layer", tmp_path / "l.png")
    assert code == 2 and ("no alpha channel" in err or "opaque on its whole frame" in err)
    assert "--whole-image" in err and "transparen" in err and not (tmp_path / "l.png").exists()
    code, _, _ = _run(capsys, "render", path, "--layer", tmp_path / "l.png", "--whole-image", "--method", "geometric")
    assert code == 0 and np.asarray(Image.open(tmp_path / "l.png"))[..., 3].max() > 0


def test_a_large_image_gets_a_clear_limit_instead_of_pillows_bomb_error(cutout_png, tmp_path, capsys, monkeypatch):
    monkeypatch.setattr(Image, "MAX_IMAGE_PIXELS", 1000)  # Pillow alone would raise DecompressionBombError here
    code, _, err = _run(capsys, "render", cutout_png, "--layer", tmp_path / "l.png", "--max-megapixels", "0.01")
    assert code == 2 and "above the limit of 0.01" in err and "--max-megapixels 1" in err
    with warnings.catch_warnings():
        warnings.simplefilter("error")  # not even Pillow's DecompressionBombWarning
        code, _, err = _run(capsys, "render", cutout_png, "--layer", tmp_path / "l.png", "--method", "geometric")
    assert code == 0 and "Decompression" not in err and Image.MAX_IMAGE_PIXELS == 1000


def test_progress_is_printed_for_slow_commands(cutout_png, tmp_path, capsys, monkeypatch):
    monkeypatch.setattr(cli, "PROGRESS_AFTER", 0.0)
    code, _, err = _run(capsys, "render", cutout_png, "--layer", tmp_path / "l.png")
    assert code == 0
    for stage in ("analysing the cutout", "rendering the shadow", "writing the shadow layer"):
        assert f"] {stage}..." in err


def test_demo_checks_its_samples_folder_first(tmp_path, capsys):
    code, _, err = _run(capsys, "demo", "--out", tmp_path / "d.png", "--save-samples", tmp_path / "missing")
    assert code == 2 and "missing" in err and "no such folder" in err and _files(tmp_path) == []
    (tmp_path / "s").mkdir()
    code, out, _ = _run(
        capsys, "demo", "--out", tmp_path / "d.png", "--save-samples", tmp_path / "s", "--method", "geometric"
    )
    assert code == 0 and _files(tmp_path / "s") == ["sample_background.png", "sample_cutout.png"]
    assert out.count("wrote") == 3


@pytest.mark.parametrize("host, step", [("krita", "Python Plugin Manager"), ("gimp", "restart GIMP")])
def test_install_plugin_says_the_next_step(tmp_path, capsys, host, step):
    dest = tmp_path / ("ssn_shadow" if host == "krita" else "ssn-shadow")
    code, out, _ = _run(capsys, "install-plugin", host, "--dest", dest)
    assert code == 0 and "next:" in out and step in out


@pytest.mark.parametrize("mode", [0o600, 0o640, 0o755])
def test_a_replaced_output_keeps_its_mode(cutout_png, tmp_path, capsys, mode):
    layer = tmp_path / "l.png"
    layer.write_bytes(b"old layer")
    layer.chmod(mode)
    code, _, _ = _run(capsys, "render", cutout_png, "--layer", layer, "--method", "geometric")
    assert code == 0 and Image.open(layer).size == (W, H)
    assert layer.stat().st_mode & 0o777 == mode


def test_a_read_only_output_is_refused(cutout_png, tmp_path, capsys):
    """A 0444 file is refused (even for root, who could replace it), before any work and any write."""
    layer, composite = tmp_path / "l.png", tmp_path / "c.png"
    layer.write_bytes(b"kept")
    layer.chmod(0o444)
    code, _, err = _run(capsys, "render", cutout_png, "--composite", composite, "--layer", layer)
    assert code == 2 and f"--layer {layer}: is read-only" in err
    assert layer.read_bytes() == b"kept" and layer.stat().st_mode & 0o777 == 0o444
    assert _files(tmp_path) == ["cutout.png", "l.png"]


@pytest.mark.parametrize("exists", [True, False])
def test_an_output_path_ending_in_a_slash_is_refused(cutout_png, tmp_path, capsys, exists):
    old = tmp_path / "old.png"
    if exists:
        old.write_bytes(b"kept")
    code, _, err = _run(capsys, "render", cutout_png, "--layer", f"{old}/")
    assert code == 2 and "ends with a slash" in err
    assert _files(tmp_path) == (["cutout.png", "old.png"] if exists else ["cutout.png"])
    if exists:
        assert old.read_bytes() == b"kept"


@pytest.mark.parametrize("target_exists", [True, False])
def test_a_symlinked_output_is_written_through_to_its_target(cutout_png, tmp_path, capsys, target_exists):
    """As a shell's ``>`` does: the link stays a link, its target gets the image (and keeps its mode)."""
    (tmp_path / "art").mkdir()
    target, link = tmp_path / "art" / "shadow.png", tmp_path / "link.png"
    if target_exists:
        target.write_bytes(b"old")
        target.chmod(0o600)
    link.symlink_to(target)
    code, out, _ = _run(capsys, "render", cutout_png, "--layer", link, "--method", "geometric")
    assert code == 0 and f"wrote {link}" in out
    assert link.is_symlink() and link.resolve() == target and Image.open(target).size == (W, H)
    assert _files(tmp_path / "art") == ["shadow.png"]  # no temporary file left beside it
    if target_exists:
        assert target.stat().st_mode & 0o777 == 0o600


def test_a_special_file_is_no_output(cutout_png, tmp_path, capsys):
    """A pipe (as a device such as /dev/null would be, for root) is refused, not replaced by a PNG file."""
    pipe = tmp_path / "pipe.png"
    os.mkfifo(pipe)
    code, _, err = _run(capsys, "render", cutout_png, "--layer", pipe)
    assert code == 2 and "not a regular file" in err and pipe.is_fifo()


@pytest.mark.parametrize("option", ["--light-map", "--ao-edits"])
@pytest.mark.parametrize("depth", [200_000, 40])
def test_deeply_nested_json_files_are_refused_naming_the_file(cutout_png, tmp_path, capsys, option, depth):
    nested = tmp_path / "nested.json"
    nested.write_text("[" * depth + "]" * depth)
    code, _, err = _run(capsys, "render", cutout_png, "--layer", tmp_path / "l.png", option, nested)
    assert code == 2 and f"{nested}: " in err and "nested more than 32" in err
    assert "Traceback" not in err and not (tmp_path / "l.png").exists()


def test_an_empty_file_is_called_empty(tmp_path, capsys):
    (tmp_path / "empty.png").write_bytes(b"")
    code, _, err = _run(capsys, "render", tmp_path / "empty.png", "--layer", tmp_path / "l.png")
    assert code == 2 and f"{tmp_path / 'empty.png'}: empty file (0 bytes)" in err and "identify" not in err


def test_a_background_without_a_composite_is_refused(cutout_png, tmp_path, capsys):
    bg = tmp_path / "bg.png"
    Image.fromarray(np.full((H, W, 3), 200, np.uint8)).save(bg)
    code, _, err = _run(capsys, "render", cutout_png, "--layer", tmp_path / "l.png", "--background", bg)
    assert code == 2 and "--background" in err and "--composite" in err
    assert not (tmp_path / "l.png").exists()


@pytest.mark.parametrize(
    "args, fragment",
    [
        (["--horizon", "nan"], "horizon: expected a canvas row (a finite number of pixels from the top), got nan"),
        (["--horizon", "inf"], "got inf"),
        (["--horizon", "1e9"], "horizon: row 1e+09 is too far from the cutout for the model; give a canvas row"),
    ],
)
def test_a_camera_out_of_reach_is_answered_in_canvas_rows_and_degrees(cutout_png, tmp_path, capsys, args, fragment):
    code, _, err = _run(capsys, "render", cutout_png, "--layer", tmp_path / "l.png", "--method", "geometric", *args)
    assert code == 2 and fragment in err and "frame" not in err and "focal" not in err


def _wait_until_numpy_loads(pid: int, timeout: float = 60.0) -> None:
    """Until the process has mapped a numpy library (its heavy imports have begun) or ended."""
    deadline = time.monotonic() + timeout
    while time.monotonic() < deadline:
        try:
            if "numpy" in Path(f"/proc/{pid}/maps").read_text():
                return
        except OSError:  # it ended
            return
        time.sleep(0.002)


@pytest.mark.skipif(not Path("/proc/self/maps").exists(), reason="needs /proc to see the imports begin")
@pytest.mark.parametrize("delay", [0.0, 0.5, 1.5, 3.0])
def test_ctrl_c_exits_130_saying_what_was_written(cutout_png, tmp_path, delay):
    """SIGINT ``delay`` seconds after numpy begins to load (Python's own start-up, before any of ssn-shadow
    runs, is not ours to answer): while the imports run, the model loads or the shadow renders, never a
    traceback, always status 130 and what was written."""
    layer = tmp_path / "l.png"
    proc = subprocess.Popen(
        [sys.executable, "-m", "ssn_engine", "render", str(cutout_png), "--layer", str(layer)],
        stdout=subprocess.PIPE,
        stderr=subprocess.PIPE,
        text=True,
        env=engine_env(),
    )
    _wait_until_numpy_loads(proc.pid)
    time.sleep(delay)
    proc.send_signal(signal.SIGINT)
    out, err = proc.communicate(timeout=120)
    assert "Traceback" not in err and "KeyboardInterrupt" not in err, err
    if proc.returncode == 0:  # it had finished: all written
        assert f"wrote {layer}" in out and layer.exists()
    else:
        assert proc.returncode == 130, (proc.returncode, err)
        written = layer.exists()
        assert ("interrupted, wrote" if written else "ssn-shadow: interrupted, nothing written") in err, err
