"""A few training steps on the stand-in store: files, resume, schedule, evaluation."""

from __future__ import annotations

import csv

import numpy as np
import pytest

torch = pytest.importorskip("torch")

from test_train_standin import FakeStore, tiny_run_args  # noqa: E402

from training import checkpoint  # noqa: E402
from training.train import main, parse_args  # noqa: E402
from training.trainer import lr_at  # noqa: E402

TINY = tiny_run_args(16, 2, "--log-every", "1", "--elms-per-view", "2")


def _run(tmp_path, module, steps, extra=()):
    run = tmp_path / module
    argv = ["--module", module, "--run", str(run), "--steps", str(steps), *TINY, *extra]
    assert main(argv, store=FakeStore(res=32)) == 0
    return run


@pytest.mark.parametrize(
    "module,extra",
    [
        ("aop", []),
        ("sr", []),
        ("sr", ["--target", "irradiance"]),
        ("aop", ["--flip"]),
        ("sr", ["--flip"]),
        ("sr", ["--balance-kinds"]),
        ("sr", ["--card", "--lights", "mix"]),
    ],
)
def test_training_writes_checkpoints_logs_and_figures(tmp_path, module, extra):
    run = _run(tmp_path, module, 4, extra)
    for name in ("last.pt", "best.pt", "log.csv", "loss.png", "samples_latest.png", "config.json"):
        assert (run / name).is_file(), name
    rows = list(csv.DictReader((run / "log.csv").open()))
    assert [int(r["step"]) for r in rows] == [1, 2, 3, 4]
    assert all(np.isfinite(float(r["train_loss"])) for r in rows)
    ck = checkpoint.load(run / "last.pt")
    assert ck["step"] == 4 and ck["module"] == module


def test_resume_continues_from_the_last_checkpoint(tmp_path):
    run = _run(tmp_path, "sr", 3)
    before = checkpoint.load(run / "last.pt")
    _run(tmp_path, "sr", 5)
    after = checkpoint.load(run / "last.pt")
    assert before["step"] == 3 and after["step"] == 5
    steps = [int(r["step"]) for r in csv.DictReader((run / "log.csv").open())]
    assert steps == [1, 2, 3, 4, 5]


def test_resume_refuses_another_network(tmp_path):
    _run(tmp_path, "sr", 2)
    with pytest.raises(SystemExit):
        _run(tmp_path, "sr", 3, ["--widths", "4,8"])


def test_schedule_warms_up_then_decays():
    args = parse_args(["--module", "sr", "--run", "x", "--steps", "100", "--warmup", "10"])
    lrs = [lr_at(s, args) for s in range(100)]
    assert lrs[0] < lrs[9] == pytest.approx(1e-3)
    assert all(a >= b for a, b in zip(lrs[10:], lrs[11:], strict=False))
    assert lrs[-1] == pytest.approx(1e-5, rel=0.05)


def test_evaluate_on_the_standin(tmp_path):
    from training.evaluate import parse_args as eval_args
    from training.evaluation import evaluate

    aop = _run(tmp_path, "aop", 2) / "last.pt"
    sr = _run(tmp_path, "sr", 2) / "last.pt"
    noninv = _run(tmp_path / "n", "sr", 2, ["--target", "irradiance"]) / "last.pt"
    args = eval_args(
        [
            "--aop",
            str(aop),
            "--sr",
            str(sr),
            "--noninv",
            str(noninv),
            "--n-elms",
            "4",
            "--per-view",
            "2",
            "--out",
            str(tmp_path / "eval"),
            "--threads",
            "1",
        ]
    )
    res = evaluate(args, store=FakeStore(res=32))
    assert set(res["groups"]) == {"objects", "humans"}
    for group in res["groups"].values():
        assert set(group["metrics"]) == {"geometric", "Non-inv-SSN", "SSN", "GT-AO-SSN"}
        for m in group["metrics"].values():
            assert 0 <= m["RMSE"] <= 1 and -1 <= m["ZNCC"] <= 1
    tables = (tmp_path / "eval" / "tables.md").read_text().splitlines()
    assert sum(line.startswith("| SSN |") for line in tables) == 2
    assert (tmp_path / "eval" / "grid.png").is_file() and (tmp_path / "eval" / "ao_failures.png").is_file()
    for group in res["groups"].values():  # per pitch: the stand-in's views are at 0 and 15 degrees
        assert set(group["by_pitch"]) == {"0", "15"}
        assert sum(row["images"] for row in group["by_pitch"].values()) == group["images"]
    assert "### By camera pitch" in (tmp_path / "eval" / "tables.md").read_text()
    common = [
        "--aop",
        str(aop),
        "--sr",
        str(sr),
        "--n-elms",
        "4",
        "--per-view",
        "2",
        "--no-geometric",
        "--threads",
        "1",
    ]

    def run(name: str, *extra: str) -> dict:
        return evaluate(eval_args([*common, "--out", str(tmp_path / name), *extra]), store=FakeStore(res=32))

    floored, plain, mirrored = run("floored", "--floor", "0.5"), run("plain"), run("mirrored", "--mirror-average")
    assert floored["floor"] == 0.5 and set(floored["methods"]) == {"SSN", "GT-AO-SSN"}
    assert mirrored["networks"]["mirror_average"] and not plain["networks"]["mirror_average"]
    assert mirrored["groups"]["objects"]["metrics"]["SSN"] != plain["groups"]["objects"]["metrics"]["SSN"]


def test_geometric_cache_reproduces_the_baseline(tmp_path):
    from training.evaluate import parse_args as eval_args
    from training.evaluation import evaluate

    argv = [
        "--n-elms",
        "4",
        "--per-view",
        "1",
        "--out",
        str(tmp_path / "e"),
        "--threads",
        "1",
        "--geo-cache",
        str(tmp_path / "geo.npz"),
    ]
    first = evaluate(eval_args(argv), store=FakeStore(res=32))
    assert first["methods"] == ["geometric"] and (tmp_path / "geo.npz").is_file()
    second = evaluate(eval_args(argv), store=FakeStore(res=32))
    for g in first["groups"]:
        for k, v in first["groups"][g]["metrics"]["geometric"].items():
            assert second["groups"][g]["metrics"]["geometric"][k] == pytest.approx(v, abs=2e-3)


def test_predicted_ao_replaces_the_chosen_samples():
    from training.trainer import mix_predicted_ao

    x = {"mask": torch.rand(64, 1, 8, 8), "ao_pred": torch.full((64, 1, 8, 8), 0.25)}
    ao = torch.ones(64, 1, 8, 8)
    gen = torch.Generator().manual_seed(0)
    mixed = mix_predicted_ao(x, ao, 0.5, gen)
    replaced = (mixed == 0.25).flatten(1).all(1)
    kept = (mixed == 1.0).flatten(1).all(1)
    assert bool((replaced | kept).all()) and 16 < int(replaced.sum()) < 48  # whole samples, about half
    assert bool((ao == 1).all())  # the input is not modified
    assert torch.equal(mix_predicted_ao(x, ao, 0.0, gen), ao)


def test_sr_trains_on_predicted_ao(tmp_path):
    aop = _run(tmp_path / "a", "aop", 2) / "last.pt"
    run = _run(tmp_path, "sr", 3, ["--ao-from", str(aop), "--ao-from-prob", "1"])
    assert checkpoint.load(run / "last.pt")["args"]["ao_from"] == [str(aop)]
    aop2 = _run(tmp_path / "b", "aop", 2, ["--seed", "1"]) / "last.pt"
    run = _run(tmp_path / "c", "sr", 2, ["--ao-from", str(aop), str(aop2), "--ao-from-prob", "1"])
    assert checkpoint.load(run / "last.pt")["args"]["ao_from"] == [str(aop), str(aop2)]


def test_samples_given_the_camera_get_the_camera_aops_map(tmp_path):
    """An SR learns on the AO maps the engine feeds it: the camera AOP's (given the true camera) where the card is
    traced with the true camera, the plain AOP's where it is blind."""
    from training.batches import CachedView, predicted_ao

    plain, given = np.full((4, 4), 0.2, np.float32), np.full((4, 4), 0.7, np.float32)
    views = [CachedView((k,), plain, plain, np.zeros((0, 16), np.uint8), None, plain, given) for k in range(3)]
    picked = predicted_ao(views, np.array([True, False, True]))
    assert [float(m.mean()) for m in picked] == pytest.approx([0.7, 0.2, 0.7])
    assert [float(m.mean()) for m in predicted_ao(views, None)] == pytest.approx([0.2] * 3)

    aop = _run(tmp_path / "a", "aop", 2) / "last.pt"
    cam = _run(tmp_path / "b", "aop", 2, ["--camera"]) / "last.pt"
    extra = ["--card", "--ao-from", str(aop), "--ao-from-camera", str(cam), "--ao-from-prob", "1"]
    run = _run(tmp_path / "c", "sr", 2, extra)
    assert checkpoint.load(run / "last.pt")["args"]["ao_from_camera"] == [str(cam)]
    with pytest.raises(ValueError, match="with the camera input"):  # a plain AOP cannot stand in for one
        _run(tmp_path / "d", "sr", 1, ["--card", "--ao-from", str(aop), "--ao-from-camera", str(aop)])
    with pytest.raises(SystemExit):  # blind samples need the plain AOP's maps, and only a card tells them apart
        _run(tmp_path / "e", "sr", 1, ["--ao-from-camera", str(cam)])


def test_fine_tuning_starts_from_the_weights_with_a_fresh_schedule(tmp_path):
    base = _run(tmp_path / "base", "sr", 3)
    tuned = _run(tmp_path / "ft", "sr", 2, ["--init-from", str(base / "last.pt"), "--lr", "0", "--lr-min", "0"])
    before, after = checkpoint.load(base / "last.pt"), checkpoint.load(tuned / "last.pt")
    assert after["step"] == 2  # its own steps, not the base run's
    for k, v in before["model"].items():  # learning rate 0: the weights are the base run's
        torch.testing.assert_close(after["model"][k], v)
    with pytest.raises(SystemExit):  # an AOP cannot start an SR run
        _run(tmp_path / "bad", "aop", 1, ["--init-from", str(base / "last.pt")])


def test_an_aop_learns_the_camera_starting_as_the_aop_it_fine_tunes(tmp_path):
    """A plain AOP starts a --camera one: its first convolution gains the camera channels with zero weights, so
    before any step the new AOP gives the old one's AO under any camera; the batches carry true and moved
    cameras (a horizon set by eye misses too)."""
    from training.model import AOPNet, UNetConfig

    base = _run(tmp_path / "base", "aop", 2)
    extra = ["--camera", "--init-from", str(base / "last.pt"), "--lr", "0", "--lr-min", "0"]
    tuned = _run(tmp_path / "cam", "aop", 2, extra + ["--blind-camera-error", "0.2", "0.1"])
    before, after = checkpoint.load(base / "last.pt"), checkpoint.load(tuned / "last.pt")
    assert after["unet"]["camera"] and not before["unet"].get("camera")
    old = AOPNet(UNetConfig.from_dict(before["unet"])).eval()
    new = AOPNet(UNetConfig.from_dict(after["unet"])).eval()
    old.load_state_dict(before["model"])
    new.load_state_dict(after["model"])
    mask = torch.rand(2, 1, 16, 16)
    with torch.no_grad():
        for camera in ([[0.5, 1.2], [0.9, 1.0]], [[-0.5, 2.0], [0.1, 1.4]]):
            torch.testing.assert_close(new(mask, torch.tensor(camera)), old(mask))
    with pytest.raises(SystemExit):  # the camera is an AOP's input; an SR gets it through its card
        _run(tmp_path / "bad", "sr", 1, ["--camera"])


def test_inexact_cameras_miss_the_true_ones_by_the_given_scales():
    from training.batches import moved_cameras

    true = np.tile([[0.5, 1.2]], (4000, 1))
    moved = moved_cameras(true, 1, (0.1, 0.05), np.random.default_rng(0))
    assert abs(np.median(np.abs(moved[:, 0] - 0.5)) - 0.1 * np.log(2)) < 0.01  # the median of |Laplace(b)|: b ln 2
    assert abs(np.median(np.abs(np.log(moved[:, 1] / 1.2))) - 0.05 * np.log(2)) < 0.005


def test_zncc_term_is_the_benchmark_zncc_and_counts_a_small_shadow_like_a_large_one():
    import numpy as np

    from training.metrics import zncc
    from training.losses import Objective, zncc_loss

    rng = np.random.default_rng(1)
    large = np.zeros((32, 32), np.float32)
    large[8:30, 2:30] = 0.8  # a low sun's long shadow
    small = np.zeros((32, 32), np.float32)
    small[26:29, 12:18] = 0.8  # a high sun's small pool
    t = lambda a: torch.tensor(np.stack(a))[:, None]  # noqa: E731
    preds = [a + 0.05 * rng.random(a.shape).astype(np.float32) for a in (large, small)]
    want = 1 - np.mean([zncc(p, g) for p, g in zip(preds, (large, small), strict=True)])
    assert zncc_loss(t(preds), t([large, small])).item() == pytest.approx(want, abs=1e-5)
    # the small shadow moved by 4 pixels: a fraction of the large shadow's L2 error, the same ZNCC cost
    moved = [np.roll(large, 4, axis=1), np.roll(small, 4, axis=1)]
    l2 = [Objective("sr")(t([m]), {"target": t([g])}).item() for m, g in zip(moved, (large, small), strict=True)]
    cost = [zncc_loss(t([m]), t([g])).item() for m, g in zip(moved, (large, small), strict=True)]
    assert l2[1] < 0.5 * l2[0] and cost[1] > cost[0]
    weighted = Objective("sr", zncc_weight=0.1)(t([moved[1]]), {"target": t([small])}).item()
    assert weighted == pytest.approx(l2[1] + 0.1 * cost[1], rel=1e-5)


def test_evaluation_by_light_family_on_the_standin(tmp_path):
    from training.evaluate import main as eval_main
    from training.evaluate import parse_args as eval_args
    from training.evaluate_families import evaluate_families

    args = eval_args(
        ["--families", "sun,sky", "--per-view", "2", "--with-camera", "geometric", "--out", str(tmp_path / "fam")]
    )
    res = evaluate_families(args, store=FakeStore(res=32))
    assert set(res["families"]) == {"sun", "sky"} and res["rows"] == ["geometric", "geometric + camera"]
    sun = res["families"]["sun"]
    assert sun["images"] == 2 * res["views"] and set(sun["kinds"]) <= {"object", "human", "animal"}
    assert set(sun["pitches"]) == {"0", "15"}
    assert set(sun["geometry"]) == set(res["rows"]) and "geometry" not in res["families"]["sky"]
    text = (tmp_path / "fam" / "families.md").read_text()
    assert "### sun" in text and "median direction error" in text and "### sky" in text
    assert (tmp_path / "fam" / "sun_grid.png").is_file()
    with pytest.raises(SystemExit, match="moon"):
        eval_main(["--families", "sun,moon", "--out", str(tmp_path / "x")])


@pytest.mark.parametrize(
    "extra", [["--card-blur", "1"], ["--card", "--card-blur", "-1"], ["--card", "--card-blur", "9"]]
)
def test_a_card_blur_needs_the_card_and_a_sensible_size(tmp_path, extra):
    with pytest.raises(SystemExit):
        _run(tmp_path, "sr", 1, extra)
