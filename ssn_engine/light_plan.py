"""One render's light map split once: what is traced, what the network renders, and the shares of each.

A small light's shadow is traced at the output's resolution (:mod:`ssn_engine.hard_light`); a broad light's
comes from the network, which also renders the traced lights as Gaussians as wide, to hedge the traced shadow
(:mod:`ssn_engine.session`). :class:`LightPlan` makes that split once per render and is handed down to every
step (the network's frames, the tracer, the sum of the parts in their shares of E0, a layer's combination of
its objects' shadows), so that no step splits the light map again.
"""

from __future__ import annotations

from dataclasses import dataclass, replace
from functools import cached_property

import numpy as np

from .hard_light import traced_share
from .hemisphere import light_power, render_light_map
from .host_kit.light_map import GaussianLight, LightMap
from .host_kit.sky_map import NETWORK_SHAPE


@dataclass(frozen=True)
class LightPlan:
    """A light map (``light_map``) split into the lights to trace (``traced``) and the network's broad light
    (``broad``): each light's intensity split by :func:`ssn_engine.hard_light.traced_share` of its size."""

    light_map: LightMap
    traced: tuple[GaussianLight, ...]
    broad: LightMap
    shared: tuple[bool, ...]  # per traced light: whether a share of it is in ``broad`` too

    @classmethod
    def of(cls, light_map: LightMap, lifted: float = 0.0) -> LightPlan:
        """The plan of ``light_map``; ``lifted`` in [0, 1]: how far the object floats off the ground for the
        network (its frames show objects standing on it), which hands that share of every broad light to the
        tracer too (1: all of it traced)."""
        traced, broad, shared = [], [], []
        for light in light_map:
            small = traced_share(light.size_degrees)
            share = small + (1.0 - small) * lifted if light.intensity > 0 else 0.0
            if share > 0:
                traced.append(light if share == 1 else replace(light, intensity=light.intensity * share))
                shared.append(share < 1)
            if share < 1:
                broad.append(light if share == 0 else replace(light, intensity=light.intensity * (1 - share)))
        return cls(light_map, tuple(traced), LightMap(broad), tuple(shared))

    @cached_property
    def network_view(self) -> LightMap:
        """The traced lights as the network renders them, to hedge their traced shadow: a light wholly traced as
        a Gaussian as wide (a disk's :func:`ssn_engine.host_kit.light_map.angle_softness`; a small disk on the
        16 x 32 map is a texel or two), one shared with the broad part as it is there, so that where it is the
        only light both parts are one map (the shadow does not depend on its intensity: one network pass)."""
        return LightMap(
            [
                light if shared else GaussianLight(light.u, light.v, light.softness, light.intensity)
                for light, shared in zip(self.traced, self.shared, strict=True)
            ]
        )

    @cached_property
    def shares(self) -> np.ndarray:
        """Each light's share of the ground's unoccluded irradiance E0, the traced lights first, then the broad
        ones (zeros where nothing lights)."""
        power = light_power(LightMap([*self.traced, *self.broad.lights]))
        return power / power.sum() if power.sum() > 0 else np.zeros_like(power)

    @property
    def traced_share(self) -> float:
        """The traced lights' share of E0."""
        return float(self.shares[: len(self.traced)].sum())

    @cached_property
    def elm(self) -> np.ndarray:
        """The whole light map on the network's ELM grid (16 x 32)."""
        return render_light_map(self.light_map, NETWORK_SHAPE[0])


__all__ = ["LightPlan"]
