"""Real GIMP 3 (its chroot): what a run may replace, and the layer's opacity in the shadow.

One gimp-console session (gimp_layers_check.py) on copies of the pawn scene, the engine the host's loopback
worker (test_gimp_integration.py's fixtures):

- a re-run replaces only a layer the filter made (its parasite names the source): the user's own layer named
  "Shadow: Pawn" right below "Pawn" used to be taken for the old shadow and deleted;
- the cutout is the layer's alpha times its opacity: a 50 % layer used to cast the full shadow.
"""

from __future__ import annotations

import shutil
from pathlib import Path

import pytest
from test_gimp_integration import _exec_scene_then, chroot, run_check, worker, workdir  # noqa: F401 - fixtures

pytestmark = pytest.mark.gimp

CHECK = "gimp_layers_check.py"


@pytest.fixture(scope="module")
def layers_result(workdir):  # noqa: F811 - the imported fixture
    work, inner = workdir
    shutil.copy(Path(__file__).with_name(CHECK), work / "layers.py")
    code = f'OUT_PATH = "{inner}/out/layers.json"; {_exec_scene_then(work, inner, "layers.py")}'
    result, log = run_check(inner, code, work / "out" / "layers.json", "gimp-console layers session")
    assert "traceback" not in log.lower(), log[-6000:]
    return result


def test_a_users_layer_named_like_the_shadow_is_never_replaced(layers_result):
    """The user's "Shadow: Pawn" below Pawn survives every run, its pixels unchanged; the filter's own layer is
    added beside it, and replaced (not doubled) when the filter runs on Pawn again."""
    user = layers_result["user"]
    first, again, on_mine = user["runs"]
    assert [r["status"] for r in user["runs"]] == ["success"] * 3, user
    assert user["mine_there"] and user["mine_unchanged"], user
    mine = user["mine"]
    made = first["returned_id"]
    assert made != mine and [made, mine] == [i for _, i in first["layers"][1:3]], first  # Pawn, ours, the user's
    # a re-run on Pawn replaces the filter's layer, in its place and with its name, and keeps the user's
    assert again["returned_id"] != made and made not in [i for _, i in again["layers"]], again
    assert [i for _, i in again["layers"]][1:3] == [again["returned_id"], mine], again
    assert again["returned"] == first["returned"]
    # run on the user's layer: it is a layer like any other, and casts its own shadow below itself
    ids = [i for _, i in on_mine["layers"]]
    assert mine in ids and ids[ids.index(mine) + 1] == on_mine["returned_id"], on_mine
    assert again["returned_id"] in ids  # Pawn's shadow is still there


def test_a_half_transparent_layer_casts_a_lighter_shadow(layers_result):
    """The same pawn at 50 % opacity casts a shadow about half as dark as at 100 % (the engine turns a uniformly
    half-transparent alpha into the opaque shape's shadow at half darkness)."""
    full, half = layers_result["opacity"]["100"], layers_result["opacity"]["50"]
    assert full["status"] == half["status"] == "success", layers_result["opacity"]
    print(
        f"\nshadow peak alpha at 100 %: {full['peak']:.3f}, at 50 %: {half['peak']:.3f}; "
        f"sums {full['sum']:.1f} and {half['sum']:.1f}"
    )
    assert full["peak"] > 0.3
    assert half["peak"] <= 0.7 * full["peak"] and half["sum"] <= 0.7 * full["sum"], (full, half)
    assert half["peak"] >= 0.2 * full["peak"], (full, half)  # lighter, not gone
