"""make_dataset end to end at a tiny size: files, resume, shards, the ViewStore contract, the card."""

from __future__ import annotations

import json

import numpy as np
import pytest

from ssn_engine.hemisphere import render_light_map, soft_shadow, texel_weights
from ssn_engine.host_kit.light_map import LightMap
from training import make_dataset
from training.data import spans
from training.data.store import ViewStore

ARGS = ["--res", "32", "--workers", "1", "--seed", "7", "--sources", "procedural", "--procedural", "12"]


@pytest.fixture(scope="module")
def dataset(tmp_path_factory):
    root = tmp_path_factory.mktemp("ds")
    assert make_dataset.main(["--out", str(root), *ARGS, "--limit", "4"]) == 0
    return root


def test_layout_card_and_contact_sheet(dataset):
    meta = json.loads((dataset / "dataset.json").read_text())
    assert meta["res"] == 32 and meta["elm_rows"] == 16 and meta["samples_per_texel"] == 16
    card = json.loads((dataset / "card.json").read_text())
    assert card["meshes"] == 4 and card["views"] == 60
    assert sum(card["views_per_split"].values()) == 60
    assert (dataset / "card.md").read_text().count("| train |") == 1
    assert (dataset / "contact_sheet.png").stat().st_size > 1000


def test_store_contract(dataset):
    store = ViewStore(dataset)
    assert len(store) == 60
    ids = store.view_ids("train") + store.view_ids("val") + store.view_ids("test")
    assert sorted(ids) == list(range(60))
    assert store.view_ids(None, kind="object") == list(range(60)) and store.view_ids(None, kind="human") == []
    v = store.load(ids[0])
    assert v.mask.shape == (32, 32) and v.mask.dtype == np.float32 and 0 <= v.mask.min() and v.mask.max() <= 1
    assert v.ao.dtype == np.float32 and v.ao.max() <= 1
    assert min(store.load(i).ao.min() for i in range(0, 60, 5)) < 0.5
    assert v.occlusion.shape == (16, 32, 32, 32) and v.occlusion.dtype == np.uint8 and v.occlusion.max() > 0
    light = store.load(ids[0], with_occ=False)  # the AOP's views: no bases unpacked
    assert light.occlusion.size == 0 and np.array_equal(light.mask, v.mask) and np.array_equal(light.ao, v.ao)
    assert set(v.info) >= {"mesh_id", "split", "kind", "category", "yaw", "pitch", "fov", "source"}
    assert v.info["source"] == "procedural" and 35 <= v.info["fov"] <= 55
    # AO is A^(1/3) with A = 1 - sum_t W_t occ_t / pi (up to the uint8 rounding of occ)
    a = 1 - np.tensordot(texel_weights(16) / np.pi, v.occlusion / 255.0, axes=2)
    assert np.abs(np.cbrt(np.clip(a, 0, 1)) - v.ao).max() < 0.02


def test_shadow_batch_and_irradiance_agree_with_soft_shadow(dataset):
    store = ViewStore(dataset)
    views = [store.load(i) for i in (0, 17, 33)]
    rng = np.random.default_rng(0)
    import random

    elms = np.stack([render_light_map(LightMap.random(random.Random(k)), 16) for k in range(3)])
    occ = np.stack([v.occlusion for v in views])
    batch = store.shadow_batch(occ, elms)
    assert batch.shape == (3, 32, 32) and batch.dtype == np.float32
    for k, v in enumerate(views):
        single = store.shadow(v.occlusion, elms[k])
        np.testing.assert_allclose(batch[k], single, atol=1e-5)
        np.testing.assert_allclose(single, soft_shadow(v.occlusion / 255.0, elms[k]), atol=1e-5)
        e0 = (elms[k] * texel_weights(16)).sum()
        np.testing.assert_allclose(store.irradiance(v.occlusion, elms[k]), e0 * (1 - single), rtol=1e-4, atol=1e-5)
    assert batch.max() > 0.3
    assert not store.shadow_batch(occ, np.zeros_like(elms)).any()
    del rng


def test_resume_skips_finished_meshes_and_shards_partition(dataset, tmp_path):
    before = {p.name: p.stat().st_mtime_ns for p in (dataset / "views").iterdir()}
    assert make_dataset.main(["--out", str(dataset), *ARGS, "--limit", "4", "--no-card"]) == 0
    after = {p.name: p.stat().st_mtime_ns for p in (dataset / "views").iterdir()}
    assert before == after
    runs = [json.loads(line) for line in (dataset / "runs.jsonl").read_text().splitlines()]
    assert runs[-1]["rendered"] == 0
    # Two shards into one directory render the same items as one run, with identical data.
    for shard in ("0/2", "1/2"):
        assert make_dataset.main(["--out", str(tmp_path), *ARGS, "--limit", "4", "--shard", shard, "--no-card"]) == 0
    a, b = ViewStore(dataset), ViewStore(tmp_path)
    assert [m["mesh"]["id"] for m in a.meshes] == [m["mesh"]["id"] for m in b.meshes]
    np.testing.assert_array_equal(a.load(20).occlusion, b.load(20).occlusion)
    ia, ib = a.load(20).info, b.load(20).info
    ia.pop("render_seconds"), ib.pop("render_seconds")
    assert ia == ib


def test_interrupted_mesh_is_redone(dataset, tmp_path):
    import shutil

    root = tmp_path / "copy"
    shutil.copytree(dataset, root)
    victim = sorted((root / "views").iterdir())[1]
    (victim / "info.json").unlink()  # as if killed before the final rename
    (root / "views" / ".tmp-x-1").mkdir()
    assert make_dataset.main(["--out", str(root), *ARGS, "--limit", "4", "--no-card"]) == 0
    assert (victim / "info.json").exists() and not (root / "views" / ".tmp-x-1").exists()
    assert json.loads((root / "runs.jsonl").read_text().splitlines()[-1])["rendered"] == 1


def test_mismatched_settings_are_refused(dataset):
    with pytest.raises(SystemExit):
        make_dataset.main(["--out", str(dataset), *ARGS[:-6], "--res", "64", "--workers", "1"])


def test_continuous_cameras(dataset, tmp_path):
    """--cameras continuous: 15 views a shape at drawn yaws (any angle) and pitches (0 to 30 degrees), each
    rendered with its own camera; the paper's set refuses to be continued with them; tables group its pitches."""
    with pytest.raises(SystemExit, match="cameras"):
        make_dataset.main(["--out", str(dataset), *ARGS, "--limit", "4", "--cameras", "continuous"])
    assert make_dataset.main(["--out", str(tmp_path), *ARGS, "--limit", "2", "--cameras", "continuous"]) == 0
    store = ViewStore(tmp_path)
    infos = [store.info(i) for i in range(len(store))]
    yaws, pitches = np.array([v["yaw"] for v in infos]), np.array([v["pitch"] for v in infos])
    assert len(infos) == 30 and len(set(pitches)) == 30 and len(set(yaws)) == 30
    assert pitches.min() >= 0 and pitches.max() <= 30 and yaws.min() >= -180 and yaws.max() < 180
    assert np.abs(yaws).max() > 90  # beyond the paper's +-90
    assert json.loads((tmp_path / "dataset.json").read_text())["cameras"] == "continuous"
    assert "pitch uniform in [0, 30]" in (tmp_path / "card.md").read_text()
    from training.data.views import pitch_groups

    assert pitch_groups([15.0, 0.0, 30.0, 0.0]) == {"0": [1, 3], "15": [0], "30": [2]}
    assert pitch_groups([29.0, 0.0, 12.5, 30.0]) == {"0-10": [1], "10-20": [2], "20-30": [0, 3]}
    # the same shape seen from a drawn, not a gridded, camera: a different mask
    paper = ViewStore(dataset)
    assert not any(np.array_equal(store.load(0).mask, paper.load(i).mask) for i in range(len(paper)))
    # both camera sets of the same shapes read as one store (a fine-tune mixing them), each view from its own root
    both = ViewStore([dataset, tmp_path])
    assert len(both) == 90 and both.view_ids(None) == list(range(90))
    np.testing.assert_array_equal(both.load(60).mask, store.load(0).mask)
    np.testing.assert_array_equal(both.load(59).occlusion, paper.load(59).occlusion)
    assert both.info(60)["mesh_id"] == both.info(0)["mesh_id"] and both.info(60)["yaw"] == store.info(0)["yaw"]


def test_stores_of_other_resolutions_are_not_merged(dataset, tmp_path):
    assert make_dataset.main(["--out", str(tmp_path), "--res", "16", *ARGS[2:], "--limit", "1"]) == 0
    with pytest.raises(ValueError, match="res 16"):
        ViewStore([dataset, tmp_path])


def test_spans_round_trip_and_quantisation():
    rng = np.random.default_rng(1)
    occ = (rng.random((5, 40, 40)) < 0.1) * rng.integers(1, 256, (5, 40, 40))
    occ = occ.astype(np.uint8)
    occ[2] = 0
    s, d = spans.pack(occ)
    assert d.size < occ.size and np.array_equal(spans.unpack(s, d, 40), occ)
    s2, d2 = spans.pack_numpy(occ)
    assert np.array_equal(s, s2) and np.array_equal(d, d2)
    q = spans.quantise_counts(np.arange(17), 16)
    assert q[0] == 0 and q[16] == 255 and np.all(np.abs(q / 255 - np.arange(17) / 16) <= 0.5 / 255 + 1e-12)
