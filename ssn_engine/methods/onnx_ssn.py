"""The SSN network as two ONNX graphs: AOP (mask -> AO) and SR (mask, AO, ELM -> shadow).

A model folder holds ``model.json`` (:class:`ssn_engine.model_config.ModelConfig`) and the graphs it names
(docs/engine.md, "Model files"):
- aop.onnx: "mask" [b, 1, R, R] -> "ao" [b, 1, R, R]
- aop_camera.onnx (optional, named by ``aop_camera``): "mask" [b, 1, R, R], "camera" [b, 2] (horizon row and
  focal length in frames, pixels / N) -> "ao" [b, 1, R, R]; the AOP of calls that give the camera input: which
  rows see the ground, and how steeply it recedes there, is what a mask alone leaves open under a level camera
  (blind calls keep aop.onnx: fed the camera estimator's reading instead, this AOP did worse; docs/training.md)
- sr.onnx: "mask" [b, 1, R, R], "ao" [b, 1, R, R], "elm" [b, 16, 32] -> "shadow" [b, 1, R, R]; a
  geometry-guided SR also takes "card" [b, 1, R, R], the geometric card's shadow for the same ELM
  (:meth:`ssn_engine.methods.geometric.GeometricCard.card_shadows`, traced with the camera input when given)
- camera.onnx (optional, with a geometry-guided SR; named by ``camera``): "mask" [b, 1, 64, 64] -> "camera"
  [b, 2], the camera input read from the mask (:mod:`ssn_engine.methods.camera_estimate`), used when a call
  gives none
- surface.onnx (optional, named by ``surface``): "mask" [b, 1, R, R] (0 or 1: coverage above 0.5), "camera"
  [b, 2] (as aop_camera's) -> "height" [b, C, R, R], each covered pixel's pixel height in frames (how far below
  it, / R, the image of the ground straight below the surface it shows lies; :meth:`OnnxSSN.pixel_heights`),
  which places each pixel's surface for the hard-light tracer (:mod:`ssn_engine.hard_light`); with C = 2 also
  the object's depth there (the far surface's pixel height is the visible one's less it), where the pixel's
  segment ends
- surface_second.onnx (optional, named by ``surface_second``, only beside ``surface``): a second surface graph
  of the same contract; each pixel's height is the higher of the two readings (the depth is the first's).
  Two networks trained on different shapes each read some raised parts low (an eye-level spider's body among
  its legs, a horse's back seen from above); the higher reading keeps what either saw (docs/training.md,
  "The higher of two readings")
The ELM goes in normalised by :func:`ssn_engine.hemisphere.network_elm`.
``model.json`` may set ``output_floor``: shadow values below it are the network's
residual noise and are removed by :func:`apply_floor` (chosen on the validation split);
``output_floor_small_lights``, if set, is the floor for light maps whose light is
concentrated in a few texels (one or two small lights: a hard-edged shadow and no
faint tails), blended in by :func:`floor_for` (docs/training.md, "The output floor").
``shadow_reach`` (a geometry-guided model only), if set, keeps the shadow of one or two small lights within
that many frame pixels (N = 256) of the card's shadow and of the cutout and fades it out beyond
(:func:`reach_weights`, blended in by :func:`small_lights_share`): no occluder can cast a shadow far from both,
so what the network leaves there is haze.
``ao_gamma``, if set, calibrates the predicted AO map: ``ao ** ao_gamma`` (below 1 lightens it; chosen on the
validation split: docs/training.md, "The AO's gamma").
``card_blur`` (a geometry-guided model only), if set, blurs the card's shadow by a Gaussian of that many model
pixels before the SR sees it: the card is traced on the model's grid, and at a wedge's tip its aliased steps made
the SR leave speckles (docs/training.md, "The card blurred").
Frames are N x N (N = 256); a model trained at another R is fed resampled frames.
"""

from __future__ import annotations

import os
from concurrent.futures import ThreadPoolExecutor
from pathlib import Path
from typing import TYPE_CHECKING

import numpy as np
from scipy import ndimage

from ..frames import frame_key, nearest_fill, resample_frames
from ..hemisphere import light_concentration, network_elm
from ..host_kit.sky_map import NETWORK_SHAPE
from ..model_config import FRAME, ModelConfig, ModelConfigError
from .base import check_batch
from .camera_estimate import INPUT, estimate_cameras
from .geometric import GeometricCard, camera_at

if TYPE_CHECKING:  # imported where a model loads: the engine runs without onnxruntime until then
    import onnxruntime as ort

KEPT_ESTIMATES = 4  # masks whose estimated camera input is kept (a session needs one; a batch past it reads again)


class ModelError(RuntimeError):
    """A model file is missing, corrupt or does not match the contract; the message names it."""


_EXPECTED = {
    "aop": [({"mask": 4}, {"ao": 4})],
    "aop_camera": [({"mask": 4, "camera": 2}, {"ao": 4})],
    "sr": [({"mask": 4, "ao": 4, "elm": 3}, {"shadow": 4}), ({"mask": 4, "ao": 4, "elm": 3, "card": 4}, {"shadow": 4})],
    "camera": [({"mask": 4}, {"camera": 2})],
    "surface": [({"mask": 4, "camera": 2}, {"height": 4})],
}


def apply_floor(shadow: np.ndarray, floor: float) -> np.ndarray:
    """``(s - floor) / (1 - floor)`` clipped to [0, 1]: removes a faint noise floor, keeps full shadow at 1."""
    if floor <= 0.0:
        return np.clip(shadow, 0.0, 1.0)
    return np.clip((shadow - np.float32(floor)) / np.float32(1.0 - floor), 0.0, 1.0)


CARD_SUPPORT = 0.01  # card shadow above this counts as where an occluder casts


def reach_weights(card: np.ndarray, masks: np.ndarray, reach: float) -> np.ndarray:
    """Weights (b, R, R) in [0, 1] that keep a shadow within ``reach`` pixels of the card's shadow (above
    ``CARD_SUPPORT``) and of the cutout (mask above 0.5), both (b, R, R), and fade it out beyond: the support grown
    by ``reach`` pixels (4-connected steps), blurred by half of it and doubled, so the weight is 1 well inside."""
    out = np.empty(card.shape, np.float32)
    steps = max(1, int(round(reach)))
    for b in range(len(card)):
        support = (card[b] > CARD_SUPPORT) | (masks[b] > 0.5)
        grown = ndimage.binary_dilation(support, iterations=steps).astype(np.float32)
        out[b] = np.minimum(ndimage.gaussian_filter(grown, steps / 2) * 2, 1.0)
    return out


def blur_frames(frames: np.ndarray, sigma: float) -> np.ndarray:
    """Frames (b, R, R) blurred by a Gaussian of ``sigma`` pixels in both axes (0: as they are)."""
    if sigma <= 0.0:
        return frames
    return ndimage.gaussian_filter(frames, (0.0, sigma, sigma), mode="nearest").astype(np.float32)


SMALL_LIGHTS = (0.2, 0.7)  # light concentration from which the small-light floor blends in, and where it is whole


def small_lights_share(elms: np.ndarray) -> np.ndarray:
    """How much each ELM (n,) is one or two small lights: 0 for a sky-like map, 1 for small lights, linear in
    :func:`ssn_engine.hemisphere.light_concentration` between ``SMALL_LIGHTS``."""
    lo, hi = SMALL_LIGHTS
    return np.clip((light_concentration(elms) - lo) / (hi - lo), 0.0, 1.0)


def floor_for(share: np.ndarray, broad: float, small_lights: float) -> np.ndarray:
    """The output floor (n,) for ELMs whose :func:`small_lights_share` is ``share`` (n,): ``broad`` for a
    sky-like map, ``small_lights`` for one or two small lights, blended between."""
    return broad + (small_lights - broad) * share


def _session(path: Path, role: str, threads: int = 0) -> ort.InferenceSession:
    """The graph at ``path``, checked against ``role``'s contract; ``threads``: its intra-op threads (0: one a
    core)."""
    import onnxruntime as ort

    if not path.is_file():
        raise ModelError(f"model file missing: {path}")
    options = ort.SessionOptions()
    options.graph_optimization_level = ort.GraphOptimizationLevel.ORT_ENABLE_ALL
    options.intra_op_num_threads = threads
    # Threads wait without spinning: spinning took ~1 ms off a light change on idle cores, but where another
    # process wants the cores (the host, its UI, any other program) a spinning thread holds one the thread it waits
    # for needs, and the SR graph took 3 to 5 times as long (docs/engine.md, "Speed").
    options.add_session_config_entry("session.intra_op.allow_spinning", "0")
    options.enable_cpu_mem_arena = False  # the arena kept ~80 MB after the first AOP run; no measurable speed cost
    try:
        session = ort.InferenceSession(str(path), options, providers=["CPUExecutionProvider"])
    except Exception as exc:  # onnxruntime raises several types for bad files
        raise ModelError(f"cannot load {path}: {exc}") from None
    got_in = {i.name: len(i.shape) for i in session.get_inputs()}
    got_out = {o.name: len(o.shape) for o in session.get_outputs()}
    if (got_in, got_out) not in _EXPECTED[role]:
        expected = " or ".join(f"inputs {i} and outputs {o}" for i, o in _EXPECTED[role])
        raise ModelError(
            f"{path} does not match the {role} contract: expected {expected} (name: rank), got {got_in} and {got_out}"
        )
    return session


def _run(session: ort.InferenceSession, output: str, feeds: dict[str, np.ndarray]) -> np.ndarray:
    """The tensor ``output`` of one run of ``session`` (the contract checked by :func:`_session`: all tensors)."""
    result = session.run([output], feeds)[0]
    if not isinstance(result, np.ndarray):
        raise ModelError(f"{output}: expected a tensor output, got {type(result).__name__}")
    return result


class OnnxSSN:
    """SSN inference with onnxruntime on the CPU."""

    name = "ssn"
    resolution = FRAME

    def __init__(self, model_dir: str | Path) -> None:
        model_dir = Path(model_dir)
        card = model_dir / "model.json"
        try:
            config = ModelConfig.from_json(card.read_text())
        except FileNotFoundError:
            raise ModelError(f"model card missing: {card}") from None
        except (OSError, ModelConfigError) as exc:
            raise ModelError(f"cannot read {card}: {exc}") from None
        self.config, self.model_resolution = config, config.resolution
        self.output_floor, self.output_floor_small_lights = config.output_floor, config.small_lights_floor
        self.shadow_reach, self.ao_gamma, self.card_blur = config.shadow_reach, config.ao_gamma, config.card_blur
        self._aop = _session(model_dir / config.aop, "aop")
        self._aop_camera = _session(model_dir / config.aop_camera, "aop_camera") if config.aop_camera else None
        self._sr = _session(model_dir / config.sr, "sr")
        takes_card = "card" in {i.name for i in self._sr.get_inputs()}
        self.card: GeometricCard | None = GeometricCard(FRAME, internal=config.resolution) if takes_card else None
        self._camera = _session(model_dir / config.camera, "camera") if takes_card and config.camera else None
        second = config.surface_second if config.surface else None
        # a pair of surface graphs runs at once, each on half the cores: a small graph gains little from the second
        # core (on 2 cores the pair took 40 ms so against 47 one after the other on both)
        threads = max(1, (os.cpu_count() or 2) // 2) if second else 0
        self._surface = _session(model_dir / config.surface, "surface", threads) if config.surface else None
        self._surface_second = _session(model_dir / second, "surface", threads) if second else None
        self._estimates: dict[bytes, np.ndarray] = {}  # mask digest -> its estimated camera input
        self._check_run()

    def cameras_for(self, masks: np.ndarray, cameras: np.ndarray | None) -> np.ndarray | None:
        """The camera inputs a call uses: the given ones, else the camera estimator's reading of each mask (kept
        for the masks seen last, so moving a light does not read it again), else None (the default camera)."""
        if cameras is not None or self._camera is None:
            return cameras
        out = np.empty((len(masks), 2))
        for b, mask in enumerate(masks):
            key = frame_key(mask)
            if key not in self._estimates:
                self._estimates[key] = estimate_cameras(self._camera, mask[None])[0]
                while len(self._estimates) > KEPT_ESTIMATES:
                    del self._estimates[next(iter(self._estimates))]
            out[b] = self._estimates[key]
        return out

    def _check_run(self) -> None:
        """Run the graphs once so that a graph that loads but cannot run fails now."""
        mask = np.zeros((1, 1, self.model_resolution, self.model_resolution), np.float32)
        try:
            ao = _run(self._aop, "ao", {"mask": mask})
            if self._aop_camera is not None:
                _run(self._aop_camera, "ao", {"mask": mask, "camera": np.array([[0.5, 1.2]], np.float32)})
            feeds = {"mask": mask, "ao": ao, "elm": np.zeros((1, *NETWORK_SHAPE), np.float32)}
            if self.card is not None:
                feeds["card"] = mask
            s = _run(self._sr, "shadow", feeds)
            if self._camera is not None:  # (an empty frame would not reach the graph)
                _run(self._camera, "camera", {"mask": np.zeros((1, 1, INPUT, INPUT), np.float32)})
            for surface in (self._surface, self._surface_second):
                if surface is not None:
                    _run(surface, "height", {"mask": mask, "camera": np.array([[0.5, 1.2]], np.float32)})
        except Exception as exc:
            raise ModelError(f"model in {self.config.aop} / {self.config.sr} failed a test run: {exc}") from None
        if s.shape != mask.shape:
            raise ModelError(f"sr output has shape {s.shape}, expected {mask.shape}")

    def pixel_heights(self, masks: np.ndarray, cameras: np.ndarray | None) -> np.ndarray | None:
        """Each frame pixel's pixel heights (b, C, N, N), frame rows, read by the surface model from the masks and
        the camera inputs (the given ones, else the estimator's reading): of the surface it shows, and for a model
        that reads the object's depth (C = 2) of its far surface (where the depth there ends). Off the mask, the
        heights that put the feet on the nearest covered pixel's (a pixel the cutout's blur or fringe reaches
        stands on the surface beside it, not that many rows higher). None for a model without a surface model, or
        with no camera to read it with."""
        cameras = self.cameras_for(masks, cameras)
        if self._surface is None or cameras is None:
            return None
        m = (resample_frames(masks, self.model_resolution) > 0.5).astype(np.float32)
        frames = (np.asarray(cameras, np.float64) / FRAME).astype(np.float32)
        feeds = {"mask": m[:, None], "camera": frames}
        if self._surface_second is None:
            heights = _run(self._surface, "height", feeds)
        else:
            with ThreadPoolExecutor(1) as pool:  # (onnxruntime releases the GIL)
                later = pool.submit(_run, self._surface_second, "height", feeds)
                heights = _run(self._surface, "height", feeds)
                second = later.result()
            np.maximum(heights[:, :1], second[:, :1], out=heights[:, :1])
        if heights.shape[1] > 1:  # the depth: the far surface's pixel height is the visible one's less it
            heights = np.concatenate([heights[:, :1], heights[:, :1] - heights[:, 1:2]], axis=1)
        b, c, r = heights.shape[:3]
        rows = ((np.arange(r, dtype=np.float32) + 0.5) / r)[:, None]
        for i in range(b):  # the feet filled, not the heights
            heights[i] = nearest_fill(heights[i] + rows, m[i] > 0) - rows
        return resample_frames(heights.reshape(b * c, r, r), FRAME).reshape(b, c, FRAME, FRAME) * FRAME

    def predict_ao(self, masks: np.ndarray, cameras: np.ndarray | None = None) -> np.ndarray:
        """The AO maps (from the camera-taking AOP where the call gives the camera input and the model has one); a
        geometry-guided model also traces each mask's card here, so moving a light does not."""
        check_batch(masks, None, self.resolution, cameras=cameras)
        m = resample_frames(masks, self.model_resolution)[:, None]
        if cameras is not None and self._aop_camera is not None:
            frames = (np.asarray(cameras, np.float64) / FRAME).astype(np.float32)
            ao = _run(self._aop_camera, "ao", {"mask": m, "camera": frames})[:, 0]
        else:
            ao = _run(self._aop, "ao", {"mask": m})[:, 0]
        if self.card is not None:
            cameras = self.cameras_for(masks, cameras)
            for b, mask in enumerate(masks):
                self.card.card(mask, camera_at(cameras, b))
        ao = np.clip(resample_frames(ao, self.resolution), 0.0, 1.0)
        return ao if self.ao_gamma == 1.0 else ao**self.ao_gamma

    def render(
        self, masks: np.ndarray, ao: np.ndarray, elms: np.ndarray, cameras: np.ndarray | None = None
    ) -> np.ndarray:
        check_batch(masks, elms, self.resolution, ao, cameras)
        feeds = {
            "mask": resample_frames(masks, self.model_resolution)[:, None],
            "ao": resample_frames(ao, self.model_resolution)[:, None],
            "elm": network_elm(elms),
        }
        card = None
        if self.card is not None:
            resolved = cameras if cameras is not None else self.cameras_for(masks, None)  # a session passes its own
            card = self.card.card_shadows(masks, elms, resolved)
            feeds["card"] = blur_frames(card, self.card_blur)[:, None]
        s = _run(self._sr, "shadow", feeds)[:, 0]
        share = small_lights_share(elms)
        if card is not None and self.shadow_reach > 0 and share.any():
            # For small lights only: a broad sky's soft shadow spreads from the whole 3D object, well past the
            # flat card's (on the test split the reach cost broad skies DSSIM at pitch 30).
            reach = self.shadow_reach * self.model_resolution / FRAME
            weights = reach_weights(card, feeds["mask"][:, 0], reach)
            s = s * (1.0 - share[:, None, None] * (1.0 - weights))
        floors = floor_for(share, self.output_floor, self.output_floor_small_lights)
        s = resample_frames(s, self.resolution)
        s = np.stack([apply_floor(frame, float(f)) for frame, f in zip(s, floors, strict=True)])
        s[np.asarray(elms).max(axis=(1, 2)) <= 0] = 0.0  # no light, no shadow (conventions)
        return s
