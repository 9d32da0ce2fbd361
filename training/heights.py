"""Pixel heights: the data and the trainer of :class:`training.model.unet.HeightNet`.

    python -m training.heights make --split train --cameras continuous paper --out data/heights128/train.npz
    python -m training.heights train --data data/heights128 --run runs/hnet --minutes 38 --steps 7000

``make`` needs only the meshes (no shadow bases): each view's camera is drawn exactly as
``training.make_dataset`` draws it (:func:`training.data.generate.view_rng`), its mask is the dataset's
coverage at N = 256 resampled to R, and the nearest and farthest surface at every pixel centre come from a
z-buffer at R (:func:`training.data.depth_raster.depth_range`); pixel heights follow with the camera
(:func:`pixel_heights`, the inverse of :func:`ssn_engine.methods.height_proxy.depth_from_heights`). The camera
estimator's input is made from the coverage at N = 256 too, as the engine makes it from a cutout
(:data:`ESTIMATOR_KEYS`).
"""

from __future__ import annotations

import argparse
import json
import time
from pathlib import Path

import numpy as np

from ssn_engine.camera import Camera
from ssn_engine.frames import resample_frames
from ssn_engine.methods.camera_estimate import canonical_input, to_canonical

from .data import meshes
from .data.depth_raster import depth_range
from .data.generate import view_rng
from .data.meshes import yawed
from .data.render_bases import mask_coverage, view_camera
from .data.sources import all_items, build_mesh
from .data.views import CAMERAS, VIEWS, draw_view
from .progress import Progress

FRAME = 256  # the frame the masks are covered at (the engine's N)
R = 128
KIND_NAMES = ("object", "human", "animal")
KEYS = ("mask", "front", "back", "camera", "kind", "pitch")
ESTIMATOR_KEYS = ("estimator", "estimator_camera")  # the camera estimator's 8-bit input from the N = FRAME mask


def pixel_heights(camera: Camera, depth: np.ndarray) -> np.ndarray:
    """Pixel heights (N, N): rows from the point at ``depth`` on each pixel centre's ray down to the image of its
    foot on the ground; 0 where the depth is not finite."""
    ok = np.isfinite(depth)
    pts = camera.centre + np.where(ok, depth, 1.0)[..., None] * camera.pixel_rays()
    _, foot_row = camera.project_xyz(pts[..., 0], np.zeros_like(pts[..., 1]), pts[..., 2])
    return np.where(ok, foot_row - (np.arange(camera.n)[:, None] + 0.5), 0.0).astype(np.float32)


def view_heights(mesh: meshes.Mesh, topo: meshes.Topology, yaw: float, pitch: float, fov: float) -> dict:
    """One view at R: mask, the two pixel-height maps and the camera input (horizon row, focal length); and the
    camera estimator's input made from the mask at N = FRAME, as the engine makes it, with its target (canonical
    horizon row and focal length over N)."""
    v = np.ascontiguousarray(yawed(mesh.vertices, yaw))
    cam = view_camera(v, FRAME, fov, pitch)
    frame_mask = mask_coverage(v, mesh.faces, topo, cam, 4)
    estimator, framing = canonical_input(frame_mask)
    mask = resample_frames(frame_mask[None], R)[0]
    small = Camera(R, cam.target_height, fov=fov, pitch=pitch, shift=cam.shift * R / FRAME)
    front, back = depth_range(v, mesh.faces, small)
    return {
        "mask": mask,
        "front": pixel_heights(small, front),
        "back": pixel_heights(small, np.where(np.isfinite(front), back, np.nan)),
        "camera": (small.horizon, float(small.focal)),
        "estimator": estimator,
        "estimator_camera": np.array(to_canonical((cam.horizon, float(cam.focal)), framing)) / FRAME,
    }


def make(
    split: str,
    cameras: list[str],
    out: Path,
    seed: int = 0,
    procedural: int = 36,
    humans: int = 48,
    view_seed: int | None = None,
) -> None:
    """Write every view of ``split`` under each camera set to ``out`` (npz, float16 maps). ``view_seed`` (default:
    ``seed``, the dataset's own views) draws other views of the same items."""
    items = [it for it in all_items(("mesh", "procedural", "anny"), procedural, humans, seed) if it.split == split]
    rec: dict[str, list] = {key: [] for key in KEYS + ESTIMATOR_KEYS}
    prog = Progress(len(items) * len(cameras))
    for c, which in enumerate(cameras):
        for q, item in enumerate(items):
            mesh = build_mesh(item)
            topo = meshes.topology(mesh)
            for k in range(VIEWS):
                yaw, pitch, fov = draw_view(k, view_rng(seed if view_seed is None else view_seed, item.id, k), which)
                view = view_heights(mesh, topo, yaw, pitch, fov)
                for key in ("mask", "front", "back"):
                    rec[key].append(view[key].astype(np.float16))
                rec["camera"].append(view["camera"])
                rec["estimator"].append(np.round(view["estimator"] * 255).astype(np.uint8))
                rec["estimator_camera"].append(view["estimator_camera"])
                rec["kind"].append(KIND_NAMES.index(item.kind))
                rec["pitch"].append(pitch)
            prog.update(c * len(items) + q + 1, item.id)
    prog.close()
    out.parent.mkdir(parents=True, exist_ok=True)
    np.savez_compressed(out, **{k: np.asarray(v) for k, v in rec.items()}, cameras=np.array(cameras))


def load(paths: list[Path]) -> dict[str, np.ndarray]:
    """The views of several ``make`` files, concatenated; the camera estimator's inputs (:data:`ESTIMATOR_KEYS`)
    too where every file has them (files made before session 28 do not)."""
    parts = [np.load(p) for p in paths]
    keys = KEYS + (ESTIMATOR_KEYS if all(set(ESTIMATOR_KEYS) <= set(p.files) for p in parts) else ())
    return {k: np.concatenate([p[k] for p in parts]) for k in keys}


def targets(data: dict[str, np.ndarray], idx: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """HeightNet's targets (B, 4, R, R) in units of R and their weights (B, 1, R, R): the covered pixels."""
    maps = np.stack([data["front"][idx], data["back"][idx]], 1).astype(np.float32)
    cam = np.broadcast_to(data["camera"][idx].astype(np.float32)[:, :, None, None], (len(idx), 2, R, R))
    weight = (data["mask"][idx] > 0.5).astype(np.float32)[:, None]
    return np.concatenate([maps, cam], 1) / R, weight


def train(args: argparse.Namespace) -> None:
    import torch

    from .model.unet import HeightNet, UNetConfig

    torch.set_num_threads(args.threads)
    root = Path(args.data)
    data = load(sorted(root.glob("train*.npz")))
    val = load(sorted(root.glob("val*.npz")))
    run = Path(args.run)
    run.mkdir(parents=True, exist_ok=True)
    net = HeightNet(UNetConfig())
    opt = torch.optim.AdamW(net.parameters(), args.lr, weight_decay=1e-4)
    step, log = 0, []
    last = run / "last.pt"
    if last.is_file():
        state = torch.load(last, weights_only=False)
        net.load_state_dict(state["net"])
        opt.load_state_dict(state["opt"])
        step, log = state["step"], state["log"]
    val_idx = np.linspace(0, len(val["mask"]) - 1, args.val_views).astype(int)

    def validate() -> list[float]:
        """Mean absolute error per channel over the covered pixels of the validation views, in pixels of R."""
        net.eval()
        err, count = np.zeros(4), 0.0
        with torch.no_grad():
            for i in range(0, len(val_idx), 64):
                idx = val_idx[i : i + 64]
                t, w = (torch.from_numpy(np.ascontiguousarray(a)) for a in targets(val, idx))
                p = net(torch.from_numpy(val["mask"][idx].astype(np.float32))[:, None])
                err += ((p - t).abs() * w).sum((0, 2, 3)).numpy()
                count += float(w.sum())
        net.train()
        return (err / max(count, 1.0) * R).round(3).tolist()

    def save() -> None:
        torch.save({"net": net.state_dict(), "opt": opt.state_dict(), "step": step, "log": log}, last)

    rng = np.random.default_rng([args.seed, step])
    t0 = time.perf_counter()
    while step < args.steps and time.perf_counter() - t0 < args.minutes * 60:
        for g in opt.param_groups:  # cosine from lr to 1e-5
            g["lr"] = 1e-5 + (args.lr - 1e-5) * 0.5 * (1 + np.cos(np.pi * step / args.steps))
        idx = rng.integers(0, len(data["mask"]), args.batch)
        t, w = (torch.from_numpy(np.ascontiguousarray(a)) for a in targets(data, idx))
        x = torch.from_numpy(data["mask"][idx].astype(np.float32))[:, None]
        if rng.random() < 0.5:  # the mirrored scene: heights and camera are unchanged
            x, t, w = x.flip(-1), t.flip(-1), w.flip(-1)
        loss = ((net(x) - t).abs() * w).sum() / (w.sum() * t.shape[1] + 1)
        opt.zero_grad()
        loss.backward()
        opt.step()
        step += 1
        if step % args.val_every == 0 or step == args.steps:
            seconds = time.perf_counter() - t0
            log.append({"step": step, "loss": float(loss.detach()) * R, "val": validate(), "seconds": seconds})
            print(json.dumps(log[-1]), flush=True)
            save()
    save()


def export(checkpoint: Path, path: Path) -> float:
    """Write HeightNet's graph ("mask" [b, 1, R, R] -> "heights" [b, 4, R, R], units of R) and return its
    largest difference to the torch network on the validation masks of a ``make`` file (or random ones)."""
    import torch

    from .export import TOL, fill_norm_constants, for_export, session
    from .model.unet import HeightNet, UNetConfig

    net = HeightNet(UNetConfig())
    net.load_state_dict(torch.load(checkpoint, weights_only=False)["net"])
    net.eval()
    path.parent.mkdir(parents=True, exist_ok=True)
    example = torch.rand(2, 1, R, R)
    torch.onnx.export(
        for_export(net, example),
        (example,),
        str(path),
        input_names=["mask"],
        output_names=["heights"],
        dynamic_axes={"mask": {0: "batch"}, "heights": {0: "batch"}},
        opset_version=18,
        dynamo=False,
    )
    fill_norm_constants(path)
    x = (np.random.default_rng(0).random((4, 1, R, R)) > 0.5).astype(np.float32)
    got = session(path).run(None, {"mask": x})[0]
    with torch.no_grad():
        ref = net(torch.from_numpy(x)).numpy()
    diff = float(np.abs(got - ref).max())
    if diff > TOL:
        raise SystemExit(f"{path}: parity FAILED, max abs diff {diff:.2e} > {TOL:.0e}")
    return diff


def main(argv: list[str] | None = None) -> None:
    p = argparse.ArgumentParser(prog="python -m training.heights", description=__doc__.split("\n")[0])
    sub = p.add_subparsers(dest="command", required=True)
    m = sub.add_parser("make", help="masks, pixel heights and cameras of a split's views")
    m.add_argument("--split", required=True, choices=("train", "val", "test"))
    m.add_argument("--cameras", nargs="+", default=["continuous"], choices=CAMERAS)
    m.add_argument("--out", required=True)
    m.add_argument("--seed", type=int, default=0, help="the items' seed (procedural shapes and people)")
    m.add_argument(
        "--view-seed", type=int, help="draw other views of the same items (default: --seed, the dataset's views)"
    )
    t = sub.add_parser("train", help="train HeightNet (resumes from RUN/last.pt)")
    t.add_argument("--data", required=True, help="folder of make's train*.npz and val*.npz")
    t.add_argument("--run", required=True)
    t.add_argument("--steps", type=int, default=7000)
    t.add_argument("--minutes", type=float, default=60.0, help="stop this chunk after this long")
    t.add_argument("--batch", type=int, default=16)
    t.add_argument("--lr", type=float, default=1e-3)
    t.add_argument("--threads", type=int, default=2)
    t.add_argument("--val-every", type=int, default=250)
    t.add_argument("--val-views", type=int, default=256)
    t.add_argument("--seed", type=int, default=0)
    e = sub.add_parser("export", help="HeightNet's ONNX graph")
    e.add_argument("checkpoint")
    e.add_argument("--out", required=True, help="the graph's path (a model folder's height.onnx)")
    args = p.parse_args(argv)
    if args.command == "make":
        make(args.split, args.cameras, Path(args.out), args.seed, view_seed=args.view_seed)
    elif args.command == "export":
        print(f"{args.out}: max abs diff to torch {export(Path(args.checkpoint), Path(args.out)):.2e}")
    else:
        train(args)


if __name__ == "__main__":
    main()
