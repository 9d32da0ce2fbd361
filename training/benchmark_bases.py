"""Throughput of the occlusion-basis renderer: seconds per view and where the time goes.

    python -m training.benchmark_bases [--res 256 128] [--meshes 8] [--views 3] [--threads 1]

Renders ``--views`` views of ``--meshes`` shared meshes spread over the triangle-count
range (plus one anny human when anny is installed), one worker, and prints per-mesh
seconds per view and a breakdown of one view into its stages. A benchmark that prints
figures, not a test: numbers depend on the machine and its load.
"""

from __future__ import annotations

import argparse
import time

import numpy as np

from ssn_engine.hemisphere import stratified_directions, texel_weights
from training.data import meshes, sources, spans
from training.data import render_bases as rb
from training.data.views import view_specs


def pick_items(count: int) -> list[sources.Item]:
    items = sources.manifest_items()
    rows = {r["id"]: int(r["faces"]) for r in meshes.read_manifest()}
    items.sort(key=lambda it: rows[it.id])
    idx = np.linspace(0, len(items) - 1, count).round().astype(int)
    picked = [items[i] for i in idx]
    try:  # anny (the people) is optional here: without it the benchmark runs on the meshes alone
        import anny  # noqa: F401

        from training.data.humans import human_items

        picked.append(human_items(1, 0)[0])
    except ImportError:
        pass
    return picked


def stages(mesh, topo, yaw, pitch, fov, n, hb, samples, rng) -> dict[str, float]:
    """One view, stage by stage (same calls as render_view), seconds per stage."""
    t = {}
    t0 = time.perf_counter()
    v = np.ascontiguousarray(meshes.yawed(mesh.vertices, yaw))
    cam = rb.view_camera(v, n, fov, pitch)
    rows = rb.ground_rows(cam)
    dirs = np.ascontiguousarray(cam.to_world(stratified_directions(hb, samples, rng)).reshape(-1, samples, 3))
    normals = meshes.face_normals(v, mesh.faces)
    t["setup (camera, directions, normals)"] = time.perf_counter() - t0
    args = rb.kernel_args(v, normals, topo, rows, dirs, n)
    times = []
    for stage in (1, 2, 3):
        t0 = time.perf_counter()
        counts = rb.occlusion_counts(*args, stage=stage)
        times.append(time.perf_counter() - t0)
    t["per texel: classify faces and edges"] = times[0]
    t["per direction: visit edges, project vertices"] = max(times[1] - times[0], 0.0)
    t["per direction: scan-convert edges, running sums"] = max(times[2] - times[1], 0.0)
    t0 = time.perf_counter()
    w = (texel_weights(hb) / np.pi / samples).reshape(-1)
    np.cbrt(np.clip(1.0 - rb.weighted_sum(counts, w), 0.0, 1.0))
    t["AO"] = time.perf_counter() - t0
    t0 = time.perf_counter()
    rb.mask_coverage(v, mesh.faces, topo, cam, max(4, -(-1024 // n)))
    t["mask"] = time.perf_counter() - t0
    t0 = time.perf_counter()
    spans.pack(spans.quantise_counts(counts, samples))
    t["quantise and pack"] = time.perf_counter() - t0
    return t


def embree_seconds_per_view(mesh, n: int, hb: int, samples: int, texels: int = 32) -> float:
    """Seconds per view of brute-force shadow rays in Embree (Mitsuba 3 llvm_ad_rgb, one thread),
    extrapolated from ``texels`` texels: the alternative this renderer was chosen against."""
    import drjit as dr  # the reference extra, needed only for this comparison
    import mitsuba as mi

    mi.set_variant("llvm_ad_rgb")
    dr.set_thread_count(1)
    m = mi.Mesh("m", vertex_count=len(mesh.vertices), face_count=len(mesh.faces))
    params = mi.traverse(m)
    params["vertex_positions"] = dr.ravel(mi.TensorXf(mesh.vertices.astype(np.float32)))
    params["faces"] = dr.ravel(mi.TensorXu(mesh.faces.astype(np.uint32)))  # pyright: ignore[reportCallIssue]
    params.update()
    scene = mi.load_dict({"type": "scene", "m": m})
    cam = rb.view_camera(mesh.vertices, n, 45.0, 15.0)
    g, down = cam.ground_points()
    o = np.repeat(g[down][:, None], samples, 1).reshape(-1, 3).astype(np.float32)
    origin = mi.Point3f(o[:, 0], o[:, 1], o[:, 2])
    dirs = cam.to_world(stratified_directions(hb, samples, np.random.default_rng(0))).reshape(-1, samples, 3)
    step = max(1, len(dirs) // texels)
    seconds, used = 0.0, 0
    for t in range(0, len(dirs), step):
        d = np.repeat(dirs[t][None], down.sum(), 0).reshape(-1, 3).astype(np.float32)
        ray = mi.Ray3f(origin, mi.Vector3f(d[:, 0], d[:, 1], d[:, 2]))
        t0 = time.perf_counter()
        np.asarray(scene.ray_test(ray))
        seconds += time.perf_counter() - t0
        used += 1
    return seconds * len(dirs) / used


def parse_args(argv: list[str] | None = None) -> argparse.Namespace:
    p = argparse.ArgumentParser(prog="python -m training.benchmark_bases", description=(__doc__ or "").split("\n")[0])
    p.add_argument("--res", type=int, nargs="+", default=[256, 128])
    p.add_argument("--meshes", type=int, default=8)
    p.add_argument("--views", type=int, default=3)
    p.add_argument("--elm-rows", type=int, default=16)
    p.add_argument("--samples", type=int, default=16)
    p.add_argument("--threads", type=int, default=1)
    p.add_argument("--embree", action="store_true", help="also time Embree ray casting (needs mitsuba)")
    return p.parse_args(argv)


def main(argv: list[str] | None = None) -> None:
    args = parse_args(argv)
    rb.set_threads(args.threads)
    items = pick_items(args.meshes)
    built = [(it, sources.build_mesh(it)) for it in items]
    built = [(it, m, meshes.topology(m)) for it, m in built]
    specs = view_specs()
    pick = np.linspace(0, len(specs) - 1, args.views).round().astype(int)
    # compile every specialisation once
    rb.render_view(built[0][1], built[0][2], 0.0, 15.0, 45.0, 32, args.elm_rows, args.samples, np.random.default_rng(0))
    stages(built[0][1], built[0][2], 0.0, 15.0, 45.0, 32, args.elm_rows, args.samples, np.random.default_rng(0))
    for n in args.res:
        print(
            f"\nN = {n}, grid {args.elm_rows} x {2 * args.elm_rows}, {args.samples} directions per texel, "
            f"{args.threads} thread(s)"
        )
        print(f"{'mesh':34s} {'faces':>6s} {'s/view':>7s} {'MiB/view':>8s}")
        all_t, total = [], {}
        for it, mesh, topo in built:
            per, size = [], []
            for k in pick:
                yaw, pitch = specs[k]
                rng = np.random.default_rng([0, k])
                t0 = time.perf_counter()
                r = rb.render_view(mesh, topo, yaw, pitch, 45.0, n, args.elm_rows, args.samples, rng)
                s, d = spans.pack(spans.quantise_counts(r.counts.reshape(-1, n, n), args.samples))
                per.append(time.perf_counter() - t0)
                size.append(s.nbytes + d.nbytes + 2 * 2 * n * n)
            all_t += per
            print(f"{it.id:34s} {len(mesh.faces):6d} {np.mean(per):7.2f} {np.mean(size) / 2**20:8.2f}")
            yaw, pitch = specs[pick[len(pick) // 2]]
            rng = np.random.default_rng(1)
            for key, val in stages(mesh, topo, yaw, pitch, 45.0, n, args.elm_rows, args.samples, rng).items():
                total[key] = total.get(key, 0.0) + val
        print(f"{'mean':34s} {'':6s} {np.mean(all_t):7.2f}")
        if args.embree:
            print("Embree shadow rays (Mitsuba 3 llvm_ad_rgb, one thread, extrapolated from 32 texels):")
            for it, mesh, _ in built:
                sec = embree_seconds_per_view(mesh, n, args.elm_rows, args.samples)
                print(f"  {it.id:32s} {sec:7.2f} s/view")
        whole = sum(total.values())
        print("where the time goes (one view per mesh, summed):")
        for key, val in total.items():
            print(f"  {key:52s} {val:7.2f} s  {100 * val / whole:5.1f} %")


if __name__ == "__main__":
    main()
