"""One cutout's shadow session: frame once, predict AO once, re-render per light map.

Moving a light re-runs only the shadow renderer (SR); the AO map, and the
user's edits of it, are kept. A shadow that reaches the frame's border is
continued beyond it by the geometric card (:mod:`ssn_engine.long_shadow`).
A render splits its light map once (:class:`ssn_engine.light_plan.LightPlan`)
and hands the plan down: small lights are traced at the output's resolution
(:mod:`ssn_engine.hard_light`), kept no lighter than the network's shadow of
them (:attr:`~ssn_engine.light_plan.LightPlan.network_view`; half of it where
the camera is given: ``GIVEN_CAMERA_HEDGE``; fading as the artist lifts the
object); the network renders the rest, and the parts add up
in their shares of the ground's unoccluded irradiance E0:
s = sum_i (E0_i / E0) s_i.
"""

from __future__ import annotations

import math
from typing import Any

import numpy as np

from . import long_shadow
from .ao_edit import apply_edits
from .framing import (
    CanvasShadow,
    Framing,
    as_unit_float,
    cutout_opacity,
    frame_alpha,
    placed_sum,
    shadow_to_canvas,
)
from .hard_light import BandKey, ContactReading, ContactTracer, Kept, coverage_level
from .hemisphere import network_elm, render_light_map
from .host_kit.camera_rules import DEFAULT_FOV, FOV_RANGE
from .host_kit.geometry_rules import check_lift, check_thickness, ground_above_horizon
from .host_kit.light_map import LightMap
from .host_kit.shadow_notes import HIDDEN, NO_LIGHT
from .host_kit.sky_map import NETWORK_SHAPE
from .light_plan import LightPlan
from .methods import GeometricCard, ShadowMethod
from .methods.base import camera_limits
from .methods.geometric import camera_at
from .stripes import thread_pool

NETWORK_THREAD = "ssn-network"  # the thread the network's frames render on while the caller traces
# How much of the network's shadow of the traced lights the traced shadow is kept no lighter than, where the camera
# is given (the model's own reading of it: all). The network's soft shadow hedges against the traced geometry's
# errors; a given camera leaves fewer (docs/hard_light.md, "Which lights are traced, and how the parts combine").
GIVEN_CAMERA_HEDGE = 0.5
# A lift of this share of the object's height floats it wholly for the network (docs/engine.md, "Lift and
# thickness"): its frames show objects standing on the ground, so from there every light is traced.
LIFT_FADE = 0.05
LOWEST_BAND = 64  # rows of the cutout converted at a time while looking for its lowest pixel, from the bottom up


def camera_input(
    framing: Framing, horizon: float, fov: float = DEFAULT_FOV, clamp: bool = False
) -> tuple[float, float]:
    """The frame's camera input for the canvas camera (``horizon`` a canvas row, ``fov`` degrees).

    A field of view in :data:`FOV_RANGE` is always taken: where the cutout is so small on its canvas that the
    frame's focal length passes what the model takes (a frame field of view under 1 degree, all but parallel
    projection), the nearest it takes is used. A horizon too far from the cutout for the model is a ValueError
    in canvas rows, unless ``clamp``: a camera checked on another object of the layer (or read from its
    outline) is moved to the nearest horizon this object's model takes, never refused."""
    if not math.isfinite(horizon):
        raise ValueError(f"horizon: expected a canvas row (a finite number of pixels from the top), got {horizon}")
    h, f = framing.camera_input(horizon, fov)
    (h_lo, h_hi), (f_lo, f_hi) = camera_limits(framing.n)
    if not clamp and not h_lo <= h <= h_hi:
        lo, hi = framing.canvas_camera(h_lo, f)[0], framing.canvas_camera(h_hi, f)[0]
        raise ValueError(
            f"horizon: row {horizon:g} is too far from the cutout for the model; give a canvas row from "
            f"{math.ceil(lo)} to {math.floor(hi)}"
        )
    return float(np.clip(h, h_lo, h_hi)), float(np.clip(f, f_lo, f_hi))


def _in_fov_range(framing: Framing, cameras: np.ndarray) -> np.ndarray:
    """A model's reading (frame camera inputs (1, 2)) moved so that its canvas field of view lies in
    :data:`FOV_RANGE`: what it reports can be given back (a tiny cutout's frame camera may read wider)."""
    horizon, fov = framing.canvas_camera(*cameras[0])
    if FOV_RANGE[0] <= fov <= FOV_RANGE[1]:
        return cameras
    return np.array([camera_input(framing, horizon, float(np.clip(fov, *FOV_RANGE)), clamp=True)], cameras.dtype)


def check_layer_opacity(value: object) -> float:
    """``value`` as a float when it is a layer's opacity the engine takes (0 to 1), else ValueError."""
    if isinstance(value, bool) or not isinstance(value, (int, float)) or not 0.0 <= value <= 1.0:
        raise ValueError(f"layer_opacity: expected the layer's opacity from 0 to 1, got {value!r}")
    return float(value)


def no_shadow_reason(light_map: LightMap, shadow: CanvasShadow) -> str | None:
    """Why a rendered shadow shows nothing (:data:`NO_LIGHT` or :data:`HIDDEN`), or None when it shows."""
    if light_map.is_dark:
        return NO_LIGHT
    return HIDDEN if shadow.is_empty else None


class ShadowSession:
    """Shadow rendering for one canvas alpha with one method; ``horizon`` (a canvas row) and ``fov`` (the
    canvas's vertical field of view, degrees) give the camera, else the method assumes the default one; ``read``:
    the camera given is a model's reading (another object's in the same layer), not the artist's;
    ``layer_opacity``: the opacity the alpha does not carry (a host layer's, times its groups')."""

    def __init__(
        self,
        alpha: np.ndarray,
        method: ShadowMethod,
        horizon: float | None = None,
        fov: float | None = None,
        read: bool = False,
        clamp: bool = False,
        layer_opacity: float = 1.0,
    ) -> None:
        self.method = method
        self.mask, self.framing = frame_alpha(alpha, method.resolution)
        x0, y0, x1, y1 = self.framing.bbox
        self._cutout = alpha[y0:y1, x0:x1].copy()  # the cutout at the canvas's resolution, for the tracer
        # A half-transparent cutout lets that share of the light through: every part casts the shadow of its
        # opaque shape (the mask and the cutout divided by its body's opacity), scaled by the opacity it shows.
        self.body_opacity = cutout_opacity(self.mask)
        if 0.0 < self.body_opacity < 1.0:
            self.mask = np.minimum(self.mask / np.float32(self.body_opacity), 1.0)
        self.opacity = self.body_opacity * check_layer_opacity(layer_opacity)
        # the canvas row a lift counts from (conventions, "Lift and thickness"): the cutout's lowest pixel, below
        # which a soft or feathered edge may reach many rows farther (its bounding box's)
        self.lift_row = y0 + self._lowest_row()
        self.edits: list[dict[str, Any]] = []
        self._card: GeometricCard | None = None  # traces long shadows for methods without a card of their own
        # the network's last inputs (which lights, their ELMs, the camera), the AO it took and its frames
        self._frames_memo: tuple[tuple, np.ndarray, np.ndarray] | None = None
        # and what they made on a canvas last: the lights, clip and framing, those frames and the canvas shadows
        self._on_canvas_memo: tuple[tuple, np.ndarray, tuple[CanvasShadow, CanvasShadow | None]] | None = None
        self.lift, self.thickness = 0.0, None  # the artist's geometry (:meth:`set_geometry`)
        self.set_camera(horizon, fov, read, clamp)

    def set_camera(
        self, horizon: float | None = None, fov: float | None = None, read: bool = False, clamp: bool = False
    ) -> None:
        """Change the camera (as in the constructor; None: the method's reading or default one; ``read``: the
        one given is a model's reading, another object's, not the artist's; ``clamp``: it was checked on another
        object, so a horizon this one's model does not take is moved, not refused (:func:`camera_input`)): the AO
        is predicted again with it and the AO edits are applied to it again. The camera the method uses is
        resolved here, once per camera (``used_cameras``), so that a light change resolves none. A camera under
        whose horizon the artist's lift would put the ground above the horizon is refused (ValueError) and
        nothing changes."""
        cameras = None
        if horizon is not None:
            fov = DEFAULT_FOV if fov is None else fov
            cameras = np.array([camera_input(self.framing, horizon, fov, clamp or read)])
        elif fov is not None:
            raise ValueError("field of view: give the horizon row too (the camera input needs both)")
        resolve = getattr(self.method, "cameras_for", None)  # a model's own reading of a blind call's camera
        used = resolve(self.mask[None], cameras) if resolve is not None else cameras
        if cameras is None and used is not None:
            used = _in_fov_range(self.framing, used)
        self._check_lift(self.lift, used)
        self._tracer: ContactTracer | None = None  # made with the camera, on first use
        self._reading: ContactReading | None = None  # the cutout read for the tracer (the model's pixel heights too)
        self._kept: dict[BandKey, Kept] | None = None  # what the cards made of it (blurred copies, padded), by band
        self.cameras, self.used_cameras = cameras, used
        # the share of the network's shadow a traced light's shadow is kept no lighter than (:meth:`to_canvas`)
        self.hedge = GIVEN_CAMERA_HEDGE if cameras is not None and not read else 1.0
        self.predicted_ao = self.method.predict_ao(self.mask[None], cameras)[0]
        self.ao = apply_edits(self.predicted_ao, self.edits) if self.edits else self.predicted_ao

    def set_geometry(self, lift: float = 0.0, thickness: float | None = None) -> None:
        """Set the artist's geometry (conventions, "Lift and thickness"): ``lift`` canvas rows from the cutout's
        lowest pixel down to the image of the ground beneath the surface it shows, ``thickness`` its depth over its
        width (None: read from the outline). A ValueError names a value out of range, or a lift whose ground lies
        above the horizon."""
        lift, thickness = self.checked_geometry(lift, thickness)
        if (lift, thickness) != (self.lift, self.thickness):
            self.lift, self.thickness, self._tracer = lift, thickness, None

    def checked_geometry(self, lift: object, thickness: object) -> tuple[float, float | None]:
        """``lift`` and ``thickness`` as :meth:`set_geometry` takes them, or the ValueError it raises."""
        lift = check_lift(lift, self.framing.canvas_height)
        self._check_lift(lift, self.used_cameras)
        return lift, None if thickness is None else check_thickness(thickness)

    def _check_lift(self, lift: float, cameras: np.ndarray | None) -> None:
        """A ValueError where ``lift`` puts the ground beneath the cutout at or above the horizon of ``cameras``
        (the frame camera input in use; an object seen above the horizon floats at least that high)."""
        if cameras is None:
            return
        horizon = self.framing.canvas_camera(*cameras[0])[0]
        lowest = self.lift_row
        if ground_above_horizon(lowest, lift, horizon):
            raise ValueError(
                f"lift: {lift:g} puts the ground beneath the cutout at row {lowest + lift:.0f}, at or above the "
                f"horizon (row {horizon:.0f}); the ground lies below it: give more than {horizon - lowest:.0f}"
            )

    @property
    def lifted(self) -> float:
        """How far the object floats for the network, in [0, 1]: its lift over ``LIFT_FADE`` of its height.
        The network's frames show objects standing on the ground; this share of every light is traced instead,
        and the network's hedge of the traced lights fades by it."""
        height = self.framing.bbox[3] - self.framing.bbox[1]
        return min(1.0, self.lift / (LIFT_FADE * height))

    @property
    def thickness_read(self) -> float:
        """The thickness the outline reads as: the surface model's deepest reading over the width, for a model that
        reads the object's depth, else :func:`ssn_engine.hard_light.read_thickness`'s round cross-section."""
        return self.tracer.thickness_read

    @property
    def camera_read(self) -> dict[str, float] | None:
        """The camera the model read from the outline for a session without one: {"horizon": canvas row, "fov":
        degrees}, where an artist can start to set it; None when a camera was given or the method reads none
        (it then assumes the conventions' default)."""
        return self.camera_read_in(self.framing)

    def camera_read_in(self, framing: Framing) -> dict[str, float] | None:
        """:attr:`camera_read` on the canvas of ``framing`` (this session's, or a preview's scaled copy of it)."""
        if self.cameras is not None or self.used_cameras is None:
            return None
        horizon, fov = framing.canvas_camera(*self.used_cameras[0])
        return {"horizon": float(horizon), "fov": float(fov)}

    def set_ao_edits(self, edits: list[dict[str, Any]]) -> np.ndarray:
        """Replace the list of AO edits; returns the edited AO map."""
        ao = apply_edits(self.predicted_ao, edits)
        self.edits, self.ao = list(edits), ao
        return ao

    @property
    def tracer(self) -> ContactTracer:
        """The tracer of this cutout's small lights (made on first use, with the camera the session uses)."""
        if self._tracer is None:
            self._tracer = self.make_tracer()
        return self._tracer

    def _tracer_alpha(self, rows: slice = slice(None)) -> np.ndarray:
        """The cutout (``rows`` of its crop) as the tracer reads it: float coverage, divided by its body's opacity
        (:attr:`body_opacity`: a half-transparent cutout casts the shadow of its opaque shape)."""
        cutout = as_unit_float(self._cutout[rows])
        if 0.0 < self.body_opacity < 1.0:
            np.minimum(cutout / np.float32(self.body_opacity), 1.0, out=cutout)
        return cutout

    def _lowest_row(self) -> int:
        """The row of the cutout's crop a lift counts from: :func:`~ssn_engine.hard_light.lowest_pixel`'s, read
        a band of rows at a time from the bottom up (a canvas-sized crop is not converted whole for it)."""
        top = float(as_unit_float(np.asarray([np.nanmax(self._cutout)]))[0])  # (framing found it not empty)
        level = coverage_level(min(1.0, top / self.body_opacity) if 0.0 < self.body_opacity < 1.0 else top)
        for stop in range(len(self._cutout), 0, -LOWEST_BAND):
            start = max(0, stop - LOWEST_BAND)
            rows = np.flatnonzero((self._tracer_alpha(slice(start, stop)) >= level).any(axis=1))
            if rows.size:
                return start + int(rows[-1])
        return len(self._cutout) - 1

    def make_tracer(self, reuse_reading: bool = True) -> ContactTracer:
        """A new tracer of this cutout. The cutout's reading (where each pixel's surface lies, for a model that
        reads pixel heights, its depth and its contact line: :class:`ContactReading`) is made once per camera and
        kept, so a change of the artist's geometry redoes only the cards (``reuse_reading`` False reads again)."""
        camera = camera_at(self.used_cameras, 0)
        if self._reading is None or not reuse_reading:
            read = getattr(self.method, "pixel_heights", None)
            heights = read(self.mask[None], self.used_cameras) if read is not None else None
            cutout = self._tracer_alpha()
            self._reading = ContactReading.of(cutout, self.framing, camera, None if heights is None else heights[0])
            self._kept = None
        tracer = ContactTracer.of_reading(self._reading, self.framing, camera, self.lift, self.thickness, self._kept)
        self._kept = tracer.kept  # another lift or thickness of the same reading takes them over
        return tracer

    def render_frame(self, plan: LightPlan) -> np.ndarray:
        """The network's frame shadows (2, N, N) of a light plan: of its broad lights (those not traced), and of
        its small lights as the network sees them (:attr:`LightPlan.network_view`), which give the traced shadow the
        object's extent and contact (:meth:`to_canvas`); zeros for a part without light."""
        maps = [plan.broad, plan.network_view if self._hedge > 0 else LightMap([])]
        out = np.zeros((2, *self.mask.shape), np.float32)
        lit = [i for i, part in enumerate(maps) if not part.is_dark]
        if not lit:
            return out
        elms = np.stack([render_light_map(maps[i], NETWORK_SHAPE[0]) for i in lit])
        # the network's inputs as last time (a lift or thickness dragged under the same light): its frames again
        key = (tuple(lit), elms.tobytes(), None if self.used_cameras is None else self.used_cameras.tobytes())
        memo = self._frames_memo
        if memo is not None and memo[0] == key and memo[1] is self.ao:
            out[lit] = memo[2] * np.float32(self.opacity)
            return out
        # one light between small and broad is in both parts as one map (up to its intensity): one pass
        same = len(lit) == 2 and np.allclose(network_elm(elms[0]), network_elm(elms[1]), rtol=0.0, atol=1e-6)
        runs = elms[:1] if same else elms
        masks, ao = np.repeat(self.mask[None], len(runs), 0), np.repeat(self.ao[None], len(runs), 0)
        cameras = None if self.used_cameras is None else np.repeat(self.used_cameras, len(runs), 0)
        frames = self.method.render(masks, ao, runs, cameras)
        self._frames_memo = (key, self.ao, frames)
        out[lit] = frames * np.float32(self.opacity)
        return out

    def to_canvas(
        self, frames: np.ndarray, plan: LightPlan, clip: bool = True, framing: Framing | None = None
    ) -> CanvasShadow:
        """The shadow of a light plan at canvas resolution (or on ``framing``'s canvas: a preview's, from
        :meth:`Framing.scaled`), cropped to its visible part, from the network's frames of :meth:`render_frame`.

        The broad lights' frame is enlarged. The small lights are traced on the canvas's pixels, added in their
        shares of E0, and where the network's shadow of them (:attr:`LightPlan.network_view`) is darker (the
        object's extent in depth, its contact), that is kept: s_small = max(traced, h network), h =
        ``GIVEN_CAMERA_HEDGE`` where the camera is given, else 1 (faded as the object floats: :attr:`lifted`).
        The two parts add up in their shares of E0."""
        framing = framing or self.framing
        key = self._canvas_key(plan, clip, framing)
        parts = self._traced(plan, clip, framing)
        return _combined(self._network_shadows(frames, plan, clip, framing, key), parts, plan, self._hedge)

    def _canvas_key(self, plan: LightPlan, clip: bool, framing: Framing) -> tuple:
        """What the network's shadows on a canvas depend on besides its frames (:meth:`_network_shadows`); the
        shadows kept of another are dropped now, not kept while the new ones are made."""
        key = (plan.broad, plan.network_view if plan.traced else None, clip, framing)
        if self._on_canvas_memo is not None and self._on_canvas_memo[0] != key:
            self._on_canvas_memo = None
        return key

    def _network_shadows(
        self, frames: np.ndarray, plan: LightPlan, clip: bool, framing: Framing, key: tuple
    ) -> tuple[CanvasShadow, CanvasShadow | None]:
        """The network's frames on ``framing``'s canvas: of the broad lights (without traced ones, the whole
        shadow), and of the traced lights as Gaussians (None without them). The same frames of the same lights on
        the same canvas (``key``) as last time (a lift or thickness dragged) give the same shadows, enlarged
        once."""
        memo = self._on_canvas_memo
        if memo is not None and memo[0] == key and np.array_equal(memo[1], frames):
            return memo[2]
        if not plan.traced:
            shadows = self._network_canvas(frames[0], plan.broad, clip, framing), None
        else:
            broad = plan.broad
            wide = CanvasShadow.nothing() if broad.is_dark else self._network_canvas(frames[0], broad, clip, framing)
            shadows = wide, self._network_canvas(frames[1], plan.network_view, clip, framing)
        self._on_canvas_memo = (key, frames.copy(), shadows)
        return shadows

    def _traced(self, plan: LightPlan, clip: bool, framing: Framing) -> list[tuple[float, np.ndarray, int, int]]:
        """The traced lights' shadows on ``framing``'s canvas, each with its share of their E0, scaled by the
        cutout's opacity."""
        small = plan.traced_share
        if not plan.traced or small <= 0:
            return []
        return [
            (share * self.opacity / small, *self.tracer.shadow(light.u, light.v, light.size_degrees, framing, clip))
            for light, share in zip(plan.traced, plan.shares[: len(plan.traced)], strict=True)
        ]

    def _network_canvas(self, frame: np.ndarray, light_map: LightMap, clip: bool, framing: Framing) -> CanvasShadow:
        """The network's frame shadow of ``light_map`` on ``framing``'s canvas, continued beyond the frame's
        border by the geometric card where it reaches it."""
        if not long_shadow.reaches_border(frame):
            return shadow_to_canvas(frame, framing, clip=clip)
        card = self.method if isinstance(self.method, GeometricCard) else getattr(self.method, "card", None)
        if card is None:
            self._card = self._card or GeometricCard(self.method.resolution)
            card = self._card
        elm = render_light_map(light_map, NETWORK_SHAPE[0])
        wide = self.opacity * card.extended_shadow(
            self.mask, elm, camera_at(self.used_cameras, 0), long_shadow.MARGIN, long_shadow.CELL
        )
        window = (*framing.to_frame(0, 0), *framing.to_frame(framing.canvas_width, framing.canvas_height))
        values, origin = long_shadow.extend(frame, wide, window=window if clip else None)
        return shadow_to_canvas(values, framing, origin, clip)

    @property
    def _hedge(self) -> float:
        """The share of the network's shadow of the traced lights the traced shadow is kept no lighter than:
        :attr:`hedge`, faded as the object floats (:attr:`lifted`)."""
        return self.hedge * (1.0 - self.lifted)

    def plan(self, light_map: LightMap) -> LightPlan:
        """The :class:`LightPlan` of ``light_map`` for this object (as far as it floats, :attr:`lifted`)."""
        return LightPlan.of(light_map, self.lifted)

    def render(self, light_map: LightMap, framing: Framing | None = None, clip: bool = True) -> CanvasShadow:
        """The shadow of ``light_map`` at canvas resolution, or on ``framing``'s canvas: :meth:`render_plan` of
        its :meth:`plan`."""
        return self.render_plan(self.plan(light_map), framing, clip)

    def render_plan(self, plan: LightPlan, framing: Framing | None = None, clip: bool = True) -> CanvasShadow:
        """:meth:`to_canvas` of :meth:`render_frame` for a light plan made once by the caller, the network's
        frames rendered and brought onto the canvas on a thread of their own while the small lights are traced
        (both release the GIL: a sun's shadow costs about the longer of the two, not their sum)."""
        framing = framing or self.framing
        if not plan.traced:
            return self.to_canvas(self.render_frame(plan), plan, clip, framing)
        key = self._canvas_key(plan, clip, framing)
        nets = thread_pool(NETWORK_THREAD, 1).submit(
            lambda: self._network_shadows(self.render_frame(plan), plan, clip, framing, key)
        )
        parts = self._traced(plan, clip, framing)
        return _combined(nets.result(), parts, plan, self._hedge)

    def cover(self, framing: Framing) -> np.ndarray:
        """The cutout's alpha (h, w) on ``framing``'s canvas, resampled from the frame: what hides the shadow
        in a preview."""
        # with an origin: no fading at the frame's edges
        mask = shadow_to_canvas(self.mask * np.float32(self.opacity), framing, origin=(0.0, 0.0))
        return mask.full_canvas(framing.canvas_width, framing.canvas_height)


def _combined(
    nets: tuple[CanvasShadow, CanvasShadow | None],
    parts: list[tuple[float, np.ndarray, int, int]],
    plan: LightPlan,
    hedge: float,
) -> CanvasShadow:
    """:meth:`ShadowSession.to_canvas` from the network's shadows (``_network_shadows``), the traced ``parts``
    (``_traced``) and the plan's shares of E0; the traced parts kept no lighter than ``hedge`` times the
    network's shadow of them."""
    wide, net = nets
    if net is None:
        return wide
    if not plan.shares.any():
        return CanvasShadow.nothing()
    small = plan.traced_share
    values, x, y = placed_sum(parts, (net, hedge))
    if plan.broad.is_dark:
        return CanvasShadow(values, x, y)
    return CanvasShadow(*placed_sum([(small, values, x, y), (1.0 - small, wide.values, wide.x, wide.y)]))
