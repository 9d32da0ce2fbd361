"""Shadow sessions for a layer that may hold several objects: one :class:`ShadowSession` per object.

:func:`open_session` splits the layer's alpha (:func:`ssn_engine.objects.split_objects`). A layer of one object
gets a plain :class:`ShadowSession` of the whole alpha (the same pixels as ever); a layer of several gets a
:class:`LayerSession`, which frames, reads and shadows each object on its own and offers the worker and the
command line the same calls as a single session (docs/engine.md, "Several objects on one layer"):

- **Camera.** One photograph has one camera. A given horizon row and field of view apply to every object (checked
  on the largest; a smaller one whose model does not take that horizon gets the nearest it takes). Without them
  the largest object's session reads the camera from its outline, as it would alone, and the other objects get
  that reading as their camera, so that all stand on one ground under one horizon (``camera_read`` is it). The
  specks left out of every object (:mod:`ssn_engine.objects`) change no object's frame or camera.
- **Shadows** combine as light does. Under one small light a ground point in two shadows is as dark as in the
  darker one (both block the same light): the maximum. Under a broad sky each object blocks its own part of the
  sky and the blocked parts add up: ``1 - prod(1 - s_i)``, exact where the parts do not overlap. A light map is
  weighted between the two by how much of its light is one or two small lights
  (:func:`ssn_engine.methods.onnx_ssn.small_lights_share`); one map of a small light and a sky is combined by the
  blend of the two rules, not per light.
- **AO.** The layer's AO map (``ao``, ``mask``: what ``get_ao`` shows) is framed as a single session would frame
  the whole layer; it is the product of the objects' AO maps resampled there (occlusions add up as the sky's do).
  An edit's place is on that frame: a brush dab goes to each object whose frame it touches, moved and scaled
  into that frame; ``grow`` (scaled to each frame's pixels) and ``strength`` go to every object.
"""

from __future__ import annotations

import dataclasses
from typing import Any

import numpy as np
from scipy import ndimage

from .ao_edit import MAX_GROW, apply_edits
from .framing import CanvasShadow, Framing, frame_alpha, union_box
from .host_kit.light_map import LightMap
from .light_plan import LightPlan
from .methods import ShadowMethod
from .methods.onnx_ssn import small_lights_share
from .objects import LayerObjects, split_objects
from .session import ShadowSession


def open_session(
    alpha: np.ndarray,
    method: ShadowMethod,
    horizon: float | None = None,
    fov: float | None = None,
    split: bool = True,
    layer_opacity: float = 1.0,
) -> ShadowSession | LayerSession:
    """The shadow session for a layer's alpha: a :class:`ShadowSession` where it holds one object (or where
    ``split`` is False: the whole alpha as one object), else a :class:`LayerSession` of its objects.

    Parameters
    ----------
    alpha : np.ndarray
        The canvas alpha (H, W), uint8, uint16 or float.
    method : ShadowMethod
        The shadow method.
    horizon, fov : float, optional
        The camera: the horizon as a canvas row and the canvas's vertical field of view in degrees.
    split : bool
        Whether to split the alpha into objects (:func:`ssn_engine.objects.split_objects`).
    layer_opacity : float
        The opacity the alpha does not carry (a host layer's, times its groups'): every shadow is scaled by it.

    Returns
    -------
    ShadowSession or LayerSession
    """
    layer = split_objects(alpha) if split else None
    if layer is None:
        return ShadowSession(alpha, method, horizon, fov, layer_opacity=layer_opacity)
    if len(layer.objects) == 1:  # without the specks left out: they would change its frame and camera
        alpha = layer.alpha_of(0, alpha) if layer.left_out else alpha
        return ShadowSession(alpha, method, horizon, fov, layer_opacity=layer_opacity)
    return LayerSession(layer, alpha, method, horizon, fov, layer_opacity)


def combine_shadows(shadows: list[CanvasShadow], hard_share: float) -> CanvasShadow:
    """Canvas shadows of several objects as one: ``hard_share`` times their maximum (one small light) plus the
    rest times their union under a broad sky, ``1 - prod(1 - s_i)``."""
    shown = [s for s in shadows if not s.is_empty]
    if not shown:
        return CanvasShadow.nothing()
    x0, y0, x1, y1 = union_box([(s.x, s.y, s.shape[1], s.shape[0]) for s in shown])
    darkest = np.zeros((y1 - y0, x1 - x0), np.float32)
    lit = np.ones_like(darkest)
    for s in shown:
        rows, cols = slice(s.y - y0, s.y - y0 + s.shape[0]), slice(s.x - x0, s.x - x0 + s.shape[1])
        values = s.rows(slice(0, s.shape[0]))  # a new array, clipped to [0, 1]
        np.maximum(darkest[rows, cols], values, out=darkest[rows, cols])
        np.subtract(1.0, values, out=values)
        lit[rows, cols] *= values
    # in place, canvas-sized: hard_share * darkest + (1 - hard_share) * (1 - lit)
    darkest *= np.float32(hard_share)
    np.subtract(1.0, lit, out=lit)
    lit *= np.float32(1.0 - hard_share)
    darkest += lit
    return CanvasShadow(darkest, x0, y0)


class LayerSession:
    """Shadow rendering for a layer of several objects (``objects``, split from the canvas ``alpha``): one
    :class:`ShadowSession` per object (``parts``, largest first), combined (module docstring). It answers the calls
    of a :class:`ShadowSession`; ``framing`` and ``mask`` are the whole layer's, as a single session would frame
    it."""

    def __init__(
        self,
        objects: LayerObjects,
        alpha: np.ndarray,
        method: ShadowMethod,
        horizon: float | None = None,
        fov: float | None = None,
        layer_opacity: float = 1.0,
    ) -> None:
        self.method = method
        self.mask, self.framing = frame_alpha(alpha, method.resolution)
        main = ShadowSession(objects.alpha_of(0, alpha), method, horizon, fov, layer_opacity=layer_opacity)
        read = main.camera_read
        if read is not None:  # the largest object's reading, the camera of them all
            horizon, fov = read["horizon"], read["fov"]
        # one object's canvas-sized alpha at a time
        others = (
            ShadowSession(objects.alpha_of(i, alpha), method, horizon, fov, read is not None, True, layer_opacity)
            for i in range(1, len(objects.objects))
        )
        self.parts = [main, *others]
        self.edits: list[dict[str, Any]] = []
        self._analysed(read)

    def set_camera(self, horizon: float | None = None, fov: float | None = None) -> None:
        """Change the camera of every object (None: the largest object reads it again, the others take its
        reading); the AO is predicted again and the AO edits applied to it again."""
        main, *others = self.parts
        main.set_camera(horizon, fov)
        read = main.camera_read
        if read is not None:
            horizon, fov = read["horizon"], read["fov"]
        for part in others:
            part.set_camera(horizon, fov, read is not None, clamp=True)
        self._analysed(read)

    def _analysed(self, read: dict[str, float] | None) -> None:
        """The layer's camera reading (``read``, the largest object's) and AO maps, after the objects' analysis."""
        self._read = read
        self._layer_camera = None if read is None else self.framing.camera_input(read["horizon"], read["fov"])
        self.predicted_ao, self.ao = self._layer_ao("predicted_ao"), self._layer_ao("ao")

    @property
    def camera_read(self) -> dict[str, float] | None:
        """The camera read from the largest object's outline, which every object uses ({"horizon": canvas row,
        "fov": degrees}); None when a camera was given or the method reads none."""
        return self._read

    def camera_read_in(self, framing: Framing) -> dict[str, float] | None:
        """:attr:`camera_read` on the canvas of ``framing`` (this session's, or a preview's scaled copy of it)."""
        if self._layer_camera is None:
            return None
        horizon, fov = framing.canvas_camera(*self._layer_camera)
        return {"horizon": float(horizon), "fov": float(fov)}

    def _part_framing(self, part: ShadowSession, framing: Framing | None) -> Framing | None:
        """An object's framing on the canvas of ``framing`` (the layer's framing, or a preview's scaled copy of
        it); None for the object's own."""
        if framing is None or framing == self.framing:
            return None
        # ``framing`` maps its canvas onto the layer's frame (a preview scaled, a canvas grown by a margin): the
        # same canvas mapped onto the part's frame through the layer's canvas
        layer, own = self.framing, part.framing
        k = own.scale / layer.scale
        return dataclasses.replace(
            own,
            canvas_width=framing.canvas_width,
            canvas_height=framing.canvas_height,
            scale=framing.scale * k,
            offset_x=(framing.offset_x - layer.offset_x) * k + own.offset_x,
            offset_y=(framing.offset_y - layer.offset_y) * k + own.offset_y,
        )

    def _layer_ao(self, which: str) -> np.ndarray:
        """The objects' AO maps (``which``: "predicted_ao" or "ao", the edited one) resampled onto the layer's frame
        and multiplied."""
        n = self.framing.n
        centres = np.arange(n) + 0.5
        out = np.ones((n, n), np.float32)
        for part in self.parts:
            k = part.framing.scale / self.framing.scale
            cols = (centres - self.framing.offset_x) * k + part.framing.offset_x - 0.5
            rows = (centres - self.framing.offset_y) * k + part.framing.offset_y - 0.5
            grid = np.meshgrid(rows, cols, indexing="ij")
            ao = getattr(part, which)
            out *= ndimage.map_coordinates(ao, grid, order=1, mode="constant", cval=1.0).astype(np.float32)
        return np.clip(out, 0.0, 1.0)

    def _part_edits(self, part: ShadowSession, edits: list[dict[str, Any]]) -> list[dict[str, Any]]:
        """Edits placed on the layer's frame, moved and scaled into ``part``'s frame (module docstring)."""
        n, k = self.framing.n, part.framing.scale / self.framing.scale
        out: list[dict[str, Any]] = []
        for edit in edits:
            if edit["op"] == "brush":
                x = ((edit["x"] * n - self.framing.offset_x) * k + part.framing.offset_x) / n
                y = ((edit["y"] * n - self.framing.offset_y) * k + part.framing.offset_y) / n
                radius = min(edit["radius"] * k, 1.0)
                gap = np.hypot(max(0.0, -x, x - 1.0), max(0.0, -y, y - 1.0))
                if gap < radius:  # it touches this object's frame
                    out.append({**edit, "x": x, "y": y, "radius": radius})
            elif edit["op"] == "grow":
                pixels = int(np.clip(round(edit["pixels"] * k), -MAX_GROW, MAX_GROW))
                if pixels:
                    out.append({**edit, "pixels": pixels})
            else:
                out.append(edit)
        return out

    def set_ao_edits(self, edits: list[dict[str, Any]]) -> np.ndarray:
        """Replace the list of AO edits (placed on the layer's frame); returns the layer's edited AO map."""
        apply_edits(self.predicted_ao, edits)  # checks them, naming a bad one as the host sent it
        for part in self.parts:
            part.set_ao_edits(self._part_edits(part, edits))
        self.edits, self.ao = list(edits), self._layer_ao("ao")
        return self.ao

    def render(self, light_map: LightMap, framing: Framing | None = None, clip: bool = True) -> CanvasShadow:
        """The combined shadow at canvas resolution, or on ``framing``'s canvas (each object's
        :meth:`ShadowSession.render`, combined as the module docstring says)."""
        plans: dict[float, LightPlan] = {}  # one per way the objects float (one where none does)
        shadows = []
        for part in self.parts:
            if part.lifted not in plans:
                plans[part.lifted] = part.plan(light_map)
            plan = plans[part.lifted]
            shadows.append(part.render_plan(plan, self._part_framing(part, framing), clip))
        return combine_shadows(shadows, float(small_lights_share(plan.elm[None])[0]))

    def set_geometry(self, lift: float = 0.0, thickness: float | None = None) -> None:
        """The artist's geometry for every object (:meth:`ShadowSession.set_geometry`), checked on each first."""
        for part in self.parts:
            part.checked_geometry(lift, thickness)
        for part in self.parts:
            part.set_geometry(lift, thickness)

    @property
    def lift(self) -> float:
        return self.parts[0].lift

    @property
    def lift_row(self) -> int:
        """The canvas row a lift counts from for the object standing highest (its lowest pixel's): the lift whose
        ground lies below the horizon from there does from every object's (:meth:`set_geometry`)."""
        return min(part.lift_row for part in self.parts)

    @property
    def thickness(self) -> float | None:
        return self.parts[0].thickness

    @property
    def thickness_read(self) -> float:
        """The largest object's thickness as its outline reads."""
        return self.parts[0].thickness_read

    def cover(self, framing: Framing) -> np.ndarray:
        """The layer's alpha (h, w) on ``framing``'s canvas, resampled from the objects' frames."""
        covers = [part.cover(self._part_framing(part, framing) or part.framing) for part in self.parts]
        return np.maximum.reduce(covers)


__all__ = ["LayerSession", "combine_shadows", "open_session"]
