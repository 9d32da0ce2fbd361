"""ssn-shadow render and demo never cost the user a file: inputs are never overwritten, every check runs before
any work, writes are atomic, and large or odd images get a clear message."""

from __future__ import annotations

import errno
import os
import warnings

import numpy as np
import pytest
from engine_helpers import drawn_alpha
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
