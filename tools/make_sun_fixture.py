"""Write tests/data/sun_views.npz: a few test-split views with their exact shadows under single suns.

    python tools/make_sun_fixture.py --data data/ssn256

For the shipped-model test of tests/engine/test_sun_shadows.py: per view the mask (uint8), the camera input
and, for each sun of ``SUNS``, the ground-truth shadow from the view's occlusion bases (uint8). The views are
held-out shapes (test split), evenly spread over objects, animals and people and over the camera pitches.
"""

from __future__ import annotations

import argparse
import sys
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))

from ssn_engine.hemisphere import render_light_map  # noqa: E402
from ssn_engine.host_kit.light_map import GaussianLight, LightMap  # noqa: E402
from training.batches import camera_input  # noqa: E402
from training.data.store import ViewStore  # noqa: E402

SUNS = ((0.75, 15.0), (0.75, 35.0), (0.75, 60.0))  # (u, elevation in degrees): right of forward, casting left
PER_KIND = 4


def main(argv: list[str] | None = None) -> int:
    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    p.add_argument("--data", default="data/ssn256")
    p.add_argument("--out", default=str(ROOT / "tests" / "data" / "sun_views.npz"))
    args = p.parse_args(argv)
    store = ViewStore(args.data)
    picked = []
    for kind in ("object", "animal", "human"):
        ids = store.view_ids("test", kind)
        picked += [ids[int(j)] for j in np.linspace(0, len(ids) - 1, PER_KIND).round()]
    masks, shadows, cameras, names = [], [], [], []
    for i in picked:
        v, info = store.load(i), store.info(i)
        masks.append(np.rint(v.mask * 255).astype(np.uint8))
        cameras.append(camera_input(info, store.meta["res"]))
        names.append(f"{info['mesh_id']} yaw {info['yaw']:g} pitch {info['pitch']:g}")
        row = []
        for u, elevation in SUNS:
            light = LightMap([GaussianLight(u, 1.0 - elevation / 90.0, 0.002, 1.0)])
            row.append(np.rint(store.shadow(v.occlusion, render_light_map(light, store.meta["elm_rows"])) * 255))
        shadows.append(np.stack(row).astype(np.uint8))
    np.savez_compressed(
        args.out,
        masks=np.stack(masks),
        shadows=np.stack(shadows),
        cameras=np.array(cameras),
        suns=np.array(SUNS),
        names=np.array(names),
    )
    print(f"wrote {args.out}: {len(picked)} views x {len(SUNS)} suns, {Path(args.out).stat().st_size / 1e3:.0f} kB")
    return 0


if __name__ == "__main__":
    sys.exit(main())
