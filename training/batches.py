"""Training batches: cached views at the network's resolution plus random ELMs and exact ground truth.

A :class:`ViewCache` keeps, per view, the mask and AO resampled to R (PIL
bilinear, as the engine feeds the network) and the occlusion bases
area-averaged to R x R (uint8, rounded; the shadow is linear in them, so this
is the ground truth at R up to 0.5/255 per texel). When the dataset is larger
than the cache, the cache rotates: every batch replaces a few cached views
with uncached ones.

A geometry-guided SR also gets the geometric card's shadow for the same light map
(:class:`ssn_engine.methods.geometric.GeometricCard`, traced at R exactly as the
engine traces it): each cached view holds the card's 512 texel shadows, along each
texel's centre direction and over its area (the engine takes the area's for a texel
holding at least 5 % of the light), for a blind camera and for the view's true camera
input (horizon row, focal length).
The blind camera is the conventions' default camera, or (``camera_error``) the true
camera moved as the camera estimator's reading of a mask misses it (:func:`blind_camera`).

Targets, for a light map rendered to ``L`` on the dataset's Hb x 2Hb grid and
``L16`` on the network's 16 x 32 grid (``peak = max L16``):
- "shadow": s = sum_t L_t W_t occ_t / sum_t L_t W_t (the conventions' s), via the store's algebra.
- "irradiance": E = sum_t (L_t / peak) W_t (1 - occ_t), the raw irradiance in the units of the
  network's (peak-1) ELM input: the Non-inv-SSN ablation's target. s = 1 - E / E0.
"""

from __future__ import annotations

from collections import Counter
from dataclasses import dataclass, replace

import numpy as np

from ssn_engine.camera import horizon_row
from ssn_engine.frames import resample_frames
from ssn_engine.hemisphere import network_elm, texel_weights
from ssn_engine.methods.base import clamp_cameras
from ssn_engine.methods.geometric import AREA_SHARE, GeometricCard

from .elm import LightBatch, render_lights, sample_lights, sample_mixture
from .frames import area_downsample

TARGETS = ("shadow", "irradiance")


@dataclass
class CachedView:
    """One view at the network's resolution R."""

    key: tuple
    mask: np.ndarray  # (R, R) float32
    ao: np.ndarray  # (R, R) float32
    occ: np.ndarray  # (T, R*R) uint8, occ * 255
    cards: tuple[np.ndarray, np.ndarray] | None = None  # card bases (2, T, R*R) uint8: blind camera, true camera
    ao_pred: np.ndarray | None = None  # (R, R) float32: an AOP's prediction from the mask (train --ao-from)
    ao_pred_camera: np.ndarray | None = None  # (R, R) float32: and a camera AOP's, given the true camera
    camera: tuple[float, float] = (0.0, 0.0)  # the view's camera input in frames: horizon row / N, focal length / N


def camera_input(info: dict, n: int) -> tuple[float, float]:
    """A view's camera input (conventions, "Camera input"): horizon row and focal length, in pixels of the
    dataset's N x N frame."""
    return horizon_row(n, info["focal"], info["pitch"], info["shift"]), float(info["focal"])


def blind_camera(
    info: dict, n: int, error: tuple[float, float] | None, rng: np.random.Generator
) -> tuple[float, float] | None:
    """The camera a view's blind card is traced with: None (the conventions' default camera), or, given
    ``error`` = (horizon scale in frames, log focal length scale), the view's true camera moved by Laplace noise
    of those scales, within the camera input's bounds: a blind call's camera as an estimate from the mask
    misses it."""
    if error is None:
        return None
    h, f = moved_cameras(np.array([camera_input(info, n)]), n, error, rng)[0]
    return float(h), float(f)


def moved_cameras(cameras: np.ndarray, n: int, error: tuple[float, float], rng: np.random.Generator) -> np.ndarray:
    """Camera inputs (b, 2) in pixels of an n-pixel frame moved by Laplace noise of ``error`` = (horizon scale in
    frames, log focal length scale), within the camera input's bounds."""
    h = cameras[:, 0] + n * rng.laplace(0.0, error[0], len(cameras))
    f = cameras[:, 1] * np.exp(rng.laplace(0.0, error[1], len(cameras)))
    return clamp_cameras(np.stack([h, f], axis=1), n)


def card_bases(
    card: GeometricCard, mask: np.ndarray, camera: tuple[float, float] | None, resolution: int
) -> np.ndarray:
    """The shadow bases of a frame mask's card on the full R x R grid, (2, T, R*R) uint8 (x 255): every
    texel's shadow along its centre direction and over its area (:func:`card_shadow` picks one per texel, as the
    engine does); a card traced on a coarser grid is resampled as the engine resamples its shadows (the resampling
    is linear, so the bases' weighted sum is the engine's resampled shadow)."""
    traced = card.card(mask, camera)
    texels = np.arange(texel_weights(16).size)
    m = card.internal
    full = np.zeros((2, len(texels), m * m), np.float32)
    if not traced.empty:
        traced.trace()
        full[0][:, traced.valid.ravel()] = traced.bases
        full[1][:, traced.valid.ravel()] = traced.area_bases(texels)
    if m != resolution:
        full = resample_frames(full.reshape(-1, m, m), resolution).reshape(2, len(texels), -1)
    return np.rint(np.clip(full, 0.0, 1.0) * 255).astype(np.uint8)


def card_shadow(bases: np.ndarray, elm16: np.ndarray, weights: np.ndarray) -> np.ndarray:
    """The card's shadows (m, P) under light maps ``elm16`` (m, 16, 32) from :func:`card_bases` (2, T, P): each
    texel's shadow over its area where it holds at least ``AREA_SHARE`` of the light, else along its centre."""
    w = elm16.reshape(len(elm16), -1).astype(np.float64) * weights.reshape(1, -1)
    total = w.sum(axis=1, keepdims=True)
    w = np.where(total > 0, w / np.where(total > 0, total, 1.0), 0.0)
    bright = w >= AREA_SHARE
    lit = np.flatnonzero(bright.any(axis=0))  # the few texels some light map traces over their areas
    centre = (np.where(bright, 0.0, w) / 255.0).astype(np.float32) @ bases[0].astype(np.float32)
    area = (np.where(bright, w, 0.0)[:, lit] / 255.0).astype(np.float32) @ bases[1][lit].astype(np.float32)
    return np.clip(centre + area, 0.0, 1.0)


def view_key(store, i: int) -> tuple:
    """A key of view ``i`` that survives re-opening the store (ids shift when meshes are added)."""
    info = store.info(i)
    return (info["mesh_id"], float(info["yaw"]), float(info["pitch"]))


def load_view(
    store,
    i: int,
    resolution: int,
    with_occ: bool = True,
    card: GeometricCard | None = None,
    predict_ao=None,
    camera_error: tuple[float, float] | None = None,
    rng: np.random.Generator | None = None,
    predict_ao_camera=None,
) -> CachedView:
    """Load view ``i`` of ``store`` and bring it to ``resolution`` (``with_occ`` False: no bases, for AOP;
    ``card``: the bases of this card method (the geometric card) for the blind camera
    (:func:`blind_camera` of ``camera_error``, drawn with ``rng``) and the true camera; ``predict_ao``: a
    function of masks (B, R, R) -> AO maps whose prediction the view keeps; ``predict_ao_camera``: one of masks and
    camera inputs (B, 2) in frames, given the view's true camera)."""
    v = store.load(i, with_occ)
    if with_occ:
        t = v.occlusion.shape[0] * v.occlusion.shape[1]
        occ = area_downsample(np.asarray(v.occlusion).reshape(t, *v.occlusion.shape[2:]), resolution)
        occ = np.rint(occ).astype(np.uint8).reshape(t, -1)
    else:
        occ = np.zeros((0, resolution * resolution), np.uint8)
    mask = resample_frames(v.mask[None], resolution)[0]
    ao = resample_frames(v.ao[None], resolution)[0]
    n = v.mask.shape[-1]
    true_camera = camera_input(v.info, n)
    cards = None
    if card is not None:
        blind = blind_camera(v.info, n, camera_error, rng if rng is not None else np.random.default_rng(i))
        cards = (card_bases(card, v.mask, blind, resolution), card_bases(card, v.mask, true_camera, resolution))
    ao_pred = None if predict_ao is None else predict_ao(mask[None])[0]
    camera = (true_camera[0] / n, true_camera[1] / n)
    ao_pred_camera = None if predict_ao_camera is None else predict_ao_camera(mask[None], np.array([camera]))[0]
    return CachedView(view_key(store, i), mask, np.clip(ao, 0.0, 1.0), occ, cards, ao_pred, ao_pred_camera, camera)


def targets_for(occ: np.ndarray, elm_hb: np.ndarray, peak: np.ndarray, weights: np.ndarray, target: str) -> np.ndarray:
    """Ground truth for one view and m light maps: occ (T, P) uint8, elm_hb (m, Hb, 2Hb), peak (m,) -> (m, P)."""
    w = elm_hb.reshape(len(elm_hb), -1).astype(np.float64) * weights.reshape(1, -1)
    occ_f = occ.astype(np.float32)
    if target == "shadow":
        total = w.sum(axis=1, keepdims=True)
        wn = np.where(total > 0, w / np.where(total > 0, total, 1.0), 0.0) / 255.0
        return np.clip(wn.astype(np.float32) @ occ_f, 0.0, 1.0)
    if target == "irradiance":
        wn = w / np.where(peak > 0, peak, 1.0)[:, None]
        blocked = (wn / 255.0).astype(np.float32) @ occ_f
        return np.maximum(wn.sum(axis=1, keepdims=True).astype(np.float32) - blocked, 0.0)
    raise ValueError(f"target must be one of {TARGETS}, got {target!r}")


def irradiance_to_shadow(e: np.ndarray, elm_hb: np.ndarray, elm16: np.ndarray) -> np.ndarray:
    """s = 1 - E / E0 for irradiance E (n, ...) in the units of the peak-1 network ELM: E0 = sum_t (L_t / peak) W_t
    on the basis grid of ``elm_hb`` (n, Hb, 2Hb), peak = max of ``elm16`` (n, 16, 32)."""
    peak = elm16.reshape(len(elm16), -1).max(axis=1)
    e0 = (elm_hb.astype(np.float64) * texel_weights(elm_hb.shape[1])).sum(axis=(1, 2))
    e0 = np.where(peak > 0, e0 / np.where(peak > 0, peak, 1.0), 0.0).reshape((-1,) + (1,) * (e.ndim - 1))
    s = np.where(e0 > 0, 1.0 - e / np.where(e0 > 0, e0, 1.0), 0.0)
    return np.clip(s, 0.0, 1.0).astype(np.float32)


class ViewCache:
    """Views of one split at resolution R, loaded lazily, at most ``max_views`` kept; ``balance_kinds``: loaded and
    drawn so that every kind (object, human, animal) is equally likely, however many views it has."""

    def __init__(
        self,
        store,
        split: str,
        resolution: int,
        max_views: int = 300,
        kind: str | None = None,
        with_occ: bool = True,
        balance_kinds: bool = False,
        card: GeometricCard | None = None,
        predict_ao=None,
        camera_error: tuple[float, float] | None = None,
        seed: int = 0,
        predict_ao_camera=None,
    ):
        self.resolution, self.max_views, self.split, self.kind = resolution, max_views, split, kind
        self.with_occ, self.balance_kinds, self.card = with_occ, balance_kinds, card
        self.predict_ao, self.predict_ao_camera, self.camera_error = predict_ao, predict_ao_camera, camera_error
        self.rng = np.random.default_rng([seed, 2027])  # the blind cards' camera errors
        self.views: dict[tuple, CachedView] = {}
        self.open(store)

    def open(self, store) -> None:
        """(Re-)read the store's list of views (a growing dataset adds meshes)."""
        self.store = store
        self.ids = store.view_ids(self.split, self.kind)
        self.keys = {view_key(store, i): i for i in self.ids}
        self.kinds = {k: store.info(i)["kind"] for k, i in self.keys.items()}
        self.weights = texel_weights(store.meta["elm_rows"])
        self.views = {k: v for k, v in self.views.items() if k in self.keys}

    def __len__(self) -> int:
        return len(self.ids)

    def draw(self, rng: np.random.Generator, keys: list[tuple], size: int, replace: bool) -> list[tuple]:
        """``size`` of ``keys`` at random: uniformly, or with every kind equally likely (``balance_kinds``)."""
        p = None
        if self.balance_kinds:
            kinds = [self.kinds[k] for k in keys]
            count = Counter(kinds)
            p = np.array([1.0 / count[c] for c in kinds])
            p /= p.sum()
        return [keys[j] for j in rng.choice(len(keys), size=size, replace=replace, p=p)]

    def fill(self, rng: np.random.Generator, swap: int = 1, per_call: int = 4, minimum: int = 16) -> None:
        """Load up to ``per_call`` uncached views (at least ``minimum`` cached after the call) while there is
        room; when full, replace ``swap`` random cached views by uncached ones."""
        missing = [k for k in self.keys if k not in self.views]
        if not missing:
            return
        room = self.max_views - len(self.views)
        if room <= 0:
            cached = list(self.views)
            for j in rng.choice(len(cached), size=min(swap, len(cached)), replace=False):
                del self.views[cached[j]]
            room = swap
        else:
            room = min(room, max(per_call, minimum - len(self.views)))
        for k in self.draw(rng, missing, min(room, len(missing)), replace=False):
            self.views[k] = self._load(k)

    def _load(self, key: tuple) -> CachedView:
        return load_view(
            self.store,
            self.keys[key],
            self.resolution,
            self.with_occ,
            self.card,
            self.predict_ao,
            self.camera_error,
            self.rng,
            self.predict_ao_camera,
        )

    def get(self, key: tuple) -> CachedView:
        if key not in self.views:
            self.views[key] = self._load(key)
        return self.views[key]


@dataclass
class Batch:
    """Numpy arrays: mask, ao, target (B, R, R); elm (B, 16, 32) network-normalised; lights; view keys; card
    (B, R, R), the card's shadow (geometry-guided SR only), and which samples' card used the true camera; ao_pred
    (B, R, R), the AOP's predicted AO (train --ao-from); camera (B, 2), each view's camera input in frames, the
    true one or (a camera-taking AOP's sampler) where not ``true_camera`` moved as an estimate misses it."""

    mask: np.ndarray
    ao: np.ndarray
    elm: np.ndarray
    target: np.ndarray
    lights: LightBatch
    keys: list
    card: np.ndarray | None = None
    true_camera: np.ndarray | None = None
    ao_pred: np.ndarray | None = None
    camera: np.ndarray | None = None


def mirror(batch: Batch, which: np.ndarray) -> Batch:
    """Mirror the samples ``which`` (bool, (B,)) left to right: frames flip in x and the light maps in azimuth.

    The camera's vertical plane is a mirror plane of the scene (no roll; the framing shifts only vertically), and
    the conventions' azimuth a -> -a maps ELM column j to W - 1 - j (u -> 1 - u), so a mirrored sample is exactly
    the mirrored scene under the mirrored light: a second, equally valid training sample.
    """

    def flip(x: np.ndarray) -> np.ndarray:
        return np.where(which.reshape((-1,) + (1,) * (x.ndim - 1)), x[..., ::-1], x)

    lights = replace(batch.lights, u=np.where(which[:, None], 1.0 - batch.lights.u, batch.lights.u))
    maybe = lambda x: None if x is None else flip(x)
    return replace(
        batch,
        mask=flip(batch.mask),
        ao=flip(batch.ao),
        elm=flip(batch.elm),
        target=flip(batch.target),
        lights=lights,
        card=maybe(batch.card),
        ao_pred=maybe(batch.ao_pred),
    )


def make_batch(
    views: list[CachedView],
    lights: LightBatch,
    elm_rows: int,
    weights: np.ndarray,
    target: str | None = "shadow",
    true_camera: np.ndarray | None = None,
) -> Batch:
    """Ground truth for ``views[b]`` under light map ``b`` (``target`` None: no shadow target, for AOP). Views
    with card bases also get the card's shadow, traced with the true camera where ``true_camera[b]``."""
    elm_hb = render_lights(lights, elm_rows)
    elm16 = render_lights(lights, 16)
    peak = elm16.reshape(len(elm16), -1).max(axis=1)
    r = views[0].mask.shape[-1]
    out = np.zeros((len(views), r * r), np.float32)
    by_view: dict[int, list[int]] = {}
    for b, v in enumerate(views):
        by_view.setdefault(id(v), []).append(b)
    if target is not None:
        for idx in by_view.values():
            out[idx] = targets_for(views[idx[0]].occ, elm_hb[idx], peak[idx], weights, target)
    card = None
    if views[0].cards is not None:
        true_camera = np.zeros(len(views), bool) if true_camera is None else true_camera
        card = np.zeros((len(views), r * r), np.float32)
        w16 = texel_weights(16)
        groups: dict[tuple[int, bool], list[int]] = {}
        for b, v in enumerate(views):  # one conversion of the uint8 bases per view and camera
            groups.setdefault((id(v), bool(true_camera[b])), []).append(b)
        for (_, true), idx in groups.items():
            cards = views[idx[0]].cards
            assert cards is not None  # every view of a batch has its cards when the first has
            card[idx] = card_shadow(cards[int(true)], elm16[idx], w16)
        card = card.reshape(len(views), r, r)
    return Batch(
        mask=np.stack([v.mask for v in views]),
        ao=np.stack([v.ao for v in views]),
        elm=network_elm(elm16),
        target=out.reshape(len(views), r, r),
        lights=lights,
        keys=[v.key for v in views],
        card=card,
        true_camera=true_camera if card is not None else None,
        ao_pred=predicted_ao(views, true_camera if card is not None else None),
        camera=np.array([v.camera for v in views], np.float32),
    )


def predicted_ao(views: list[CachedView], true_camera: np.ndarray | None) -> np.ndarray | None:
    """The AOP's predicted AO of each sample (None without one): the camera AOP's where the sample's card is traced
    with the true camera and the view has it, as the engine runs that AOP only for calls given the camera."""
    if views[0].ao_pred is None:
        return None
    given = np.zeros(len(views), bool) if true_camera is None else true_camera
    maps = []
    for v, g in zip(views, given, strict=True):
        ao = v.ao_pred_camera if g and v.ao_pred_camera is not None else v.ao_pred
        if ao is None:
            raise ValueError(f"view {v.key} has no predicted AO where the batch's first view has one")
        maps.append(ao)
    return np.stack(maps)


def move_blind_cameras(
    batch: Batch, true_camera: np.ndarray, error: tuple[float, float], rng: np.random.Generator
) -> None:
    """A camera-taking AOP's batch: the cameras (in frames) of the samples not ``true_camera`` moved in place by
    :func:`moved_cameras`, as an estimate (or a horizon set by eye) misses the true one."""
    assert batch.camera is not None
    batch.camera[~true_camera] = moved_cameras(batch.camera[~true_camera], 1, error, rng)


class BatchSampler:
    """Random training batches: ``batch // elms_per_view`` cached views, each under ``elms_per_view`` random ELMs
    (Table 1, or a mixture of light families ``lights``); ``flip``: each sample mirrored left to right with
    probability 1/2 (:func:`mirror`); with card bases, a card traced with the true camera with probability
    ``true_camera``. The cache rotates ``swap`` views every ``swap_every`` batches (loading a view with its card
    bases costs about a second)."""

    def __init__(
        self,
        cache: ViewCache,
        batch: int,
        target: str | None = "shadow",
        elms_per_view: int = 2,
        swap: int = 1,
        max_lights: int = 50,
        flip: bool = False,
        lights: dict[str, float] | None = None,
        true_camera: float = 0.5,
        swap_every: int = 1,
    ):
        self.cache, self.batch, self.target = cache, batch, target
        self.elms_per_view, self.swap, self.max_lights, self.flip = elms_per_view, swap, max_lights, flip
        self.lights, self.true_camera, self.swap_every, self.calls = lights, true_camera, max(1, swap_every), 0

    def __call__(self, rng: np.random.Generator) -> Batch:
        if self.calls % self.swap_every == 0 or len(self.cache.views) < 16:
            self.cache.fill(rng, self.swap)
        self.calls += 1
        keys = list(self.cache.views)
        n_views = max(1, self.batch // self.elms_per_view)
        chosen = self.cache.draw(rng, keys, n_views, replace=len(keys) < n_views)
        views = [self.cache.get(chosen[b % n_views]) for b in range(self.batch)]
        if self.lights:
            lights = sample_mixture(rng, self.batch, self.lights, self.max_lights)
        else:
            lights = sample_lights(rng, self.batch, self.max_lights)
        true_camera = rng.random(self.batch) < self.true_camera
        batch = make_batch(
            views, lights, self.cache.store.meta["elm_rows"], self.cache.weights, self.target, true_camera
        )
        if batch.card is None and self.cache.camera_error is not None:  # (an SR's cameras ride in its cards)
            move_blind_cameras(batch, true_camera, self.cache.camera_error, rng)
        return mirror(batch, rng.random(self.batch) < 0.5) if self.flip else batch
