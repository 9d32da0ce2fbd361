"""Environment light maps as editable mixtures of 2D Gaussian lights.

Pure Python (stdlib only) so that the Krita and GIMP plug-ins can drive the
editor without numpy. Rendering to arrays lives in :mod:`ssn_engine.hemisphere`.

Map coordinates follow ``docs/conventions.md``: ``u`` in [0, 1] runs
across the map (azimuth -180..180 degrees, 0.5 straight ahead of the camera,
wrapping around), ``v`` in [0, 1] runs down from the zenith (0) to the
horizon (1).

A light is ``intensity * exp(-d^2 / (2 * softness))``, ``softness`` being the
paper's sigma^2. The distance ``d`` is measured in map heights on the 2:1 map,
``d^2 = (2 du)^2 + dv^2`` with ``du`` wrapped, so a light is round in the
editor.
"""

from __future__ import annotations

import json
import math
import random
from collections.abc import Callable, Iterator
from dataclasses import dataclass, field, replace
from typing import Any

from .protocol import NestingError, loads, versioned

FORMAT = "ssn-shadow-elm"
VERSION = 1

# Table 1 of the paper.
MAX_LIGHTS = 50
INTENSITY_RANGE = (0.0, 3.0)
SOFTNESS_RANGE = (1e-4, 0.1)
ASPECT = 2.0  # map width / height


class LightMapError(ValueError):
    """Invalid light-map data; the message names the offending field."""


def _number(value: Any, name: str, lo: float, hi: float) -> float:
    if isinstance(value, bool) or not isinstance(value, (int, float)):
        raise LightMapError(f"{name}: expected a number, got {value!r}")
    value = float(value)
    if not math.isfinite(value) or not lo <= value <= hi:
        raise LightMapError(f"{name}: expected a number in [{lo:g}, {hi:g}], got {value!r}")
    return value


@dataclass(frozen=True)
class GaussianLight:
    """One Gaussian light: position (u, v), softness sigma^2 and peak intensity."""

    u: float
    v: float
    softness: float = 0.01
    intensity: float = 1.0

    def __post_init__(self) -> None:
        object.__setattr__(self, "u", _number(self.u, "u", 0.0, 1.0))
        object.__setattr__(self, "v", _number(self.v, "v", 0.0, 1.0))
        object.__setattr__(self, "softness", _number(self.softness, "softness", *SOFTNESS_RANGE))
        object.__setattr__(self, "intensity", _number(self.intensity, "intensity", *INTENSITY_RANGE))

    @property
    def radius(self) -> float:
        """One standard deviation, in map heights."""
        return math.sqrt(self.softness)

    def distance_to(self, u: float, v: float) -> float:
        """Distance in map heights from the light's centre, azimuth wrapping."""
        du = abs(u - self.u) % 1.0
        du = min(du, 1.0 - du)
        return math.hypot(ASPECT * du, v - self.v)

    def to_dict(self) -> dict[str, float]:
        return {"u": self.u, "v": self.v, "softness": self.softness, "intensity": self.intensity}


def _clamp(x: float, lo: float, hi: float) -> float:
    if not math.isfinite(x):
        raise LightMapError(f"expected a finite number, got {x!r}")
    return min(max(x, lo), hi)


@dataclass
class LightMap:
    """An editable list of Gaussian lights (the editor's model)."""

    lights: list[GaussianLight] = field(default_factory=list)

    # -- editing -----------------------------------------------------------
    def add(self, u: float, v: float, softness: float = 0.01, intensity: float = 1.0) -> int:
        """Add a light (position wrapped/clamped into the map); return its index."""
        if len(self.lights) >= MAX_LIGHTS:
            raise LightMapError(f"lights: at most {MAX_LIGHTS} lights")
        self.lights.append(
            GaussianLight(
                _clamp(u, -1e9, 1e9) % 1.0,
                _clamp(v, 0.0, 1.0),
                _clamp(softness, *SOFTNESS_RANGE),
                _clamp(intensity, *INTENSITY_RANGE),
            )
        )
        return len(self.lights) - 1

    def move(self, index: int, u: float, v: float) -> None:
        """Move a light; u wraps around the azimuth, v is clamped to the map."""
        self.lights[index] = replace(self.lights[index], u=_clamp(u, -1e9, 1e9) % 1.0, v=_clamp(v, 0.0, 1.0))

    def resize(self, index: int, softness: float) -> None:
        """Set a light's softness (sigma^2), clamped to Table 1's range."""
        self.lights[index] = replace(self.lights[index], softness=_clamp(softness, *SOFTNESS_RANGE))

    def reweight(self, index: int, intensity: float) -> None:
        """Set a light's peak intensity, clamped to Table 1's range."""
        self.lights[index] = replace(self.lights[index], intensity=_clamp(intensity, *INTENSITY_RANGE))

    def delete(self, index: int) -> None:
        del self.lights[index]

    def hit_test(self, u: float, v: float, tolerance: float = 0.06) -> int | None:
        """Index of the light under (u, v), the nearest if several, else None.

        A light is hit within ``max(tolerance, its radius)`` map heights.
        """
        best, best_d = None, math.inf
        for i, light in enumerate(self.lights):
            d = light.distance_to(u, v)
            if d <= max(tolerance, light.radius) and d < best_d:
                best, best_d = i, d
        return best

    def __iter__(self) -> Iterator[GaussianLight]:
        return iter(self.lights)

    def __len__(self) -> int:
        return len(self.lights)

    @property
    def is_dark(self) -> bool:
        """No light at all: no lights, or all at intensity 0 (so no shadow either)."""
        return not any(light.intensity > 0 for light in self.lights)

    def copy(self) -> LightMap:
        return LightMap(list(self.lights))

    # -- JSON --------------------------------------------------------------
    def to_dict(self) -> dict[str, Any]:
        return {"format": FORMAT, "version": VERSION, "lights": [light.to_dict() for light in self.lights]}

    def to_json(self) -> str:
        return json.dumps(self.to_dict(), indent=2)

    @classmethod
    def from_dict(cls, data: Any) -> LightMap:
        """Parse the versioned JSON structure; errors name the field."""
        if not isinstance(data, dict):
            raise LightMapError(f"light map: expected a JSON object, got {type(data).__name__}")
        versioned(data, FORMAT, VERSION, "this ssn-shadow", LightMapError)
        lights = data.get("lights")
        if not isinstance(lights, list):
            raise LightMapError("lights: expected a list")
        if len(lights) > MAX_LIGHTS:
            raise LightMapError(f"lights: at most {MAX_LIGHTS} lights, got {len(lights)}")
        parsed = []
        for i, item in enumerate(lights):
            if not isinstance(item, dict):
                raise LightMapError(f"lights[{i}]: expected an object")
            missing = {"u", "v", "softness", "intensity"} - set(item)
            if missing:
                raise LightMapError(f"lights[{i}].{sorted(missing)[0]}: missing")
            try:
                parsed.append(GaussianLight(item["u"], item["v"], item["softness"], item["intensity"]))
            except LightMapError as exc:
                raise LightMapError(f"lights[{i}].{exc}") from None
        return cls(parsed)

    @classmethod
    def from_json(cls, text: str) -> LightMap:
        try:
            data = loads(text)
        except NestingError as exc:
            raise LightMapError(f"light map: {exc}") from None
        except json.JSONDecodeError as exc:
            raise LightMapError(f"light map: not valid JSON ({exc})") from None
        return cls.from_dict(data)

    # -- sampling ----------------------------------------------------------
    @classmethod
    def random(cls, rng: random.Random, max_lights: int = MAX_LIGHTS) -> LightMap:
        """A random light map from the paper's Table 1 ranges."""
        k = rng.randint(1, max_lights)
        return cls(
            [
                GaussianLight(
                    rng.random(),
                    rng.random(),
                    rng.uniform(SOFTNESS_RANGE[0], SOFTNESS_RANGE[1]),
                    rng.uniform(*INTENSITY_RANGE),
                )
                for _ in range(k)
            ]
        )


def _preset(*lights: tuple[float, float, float, float]) -> Callable[[], LightMap]:
    return lambda: LightMap([GaussianLight(*light) for light in lights])


# (u, v, softness, intensity). u = 0.5 is the sky behind the object (shadow
# towards the viewer); u < 0.5 is left of the view, so its shadow falls right.
PRESETS: dict[str, Callable[[], LightMap]] = {
    "high-sun": _preset((0.5, 0.12, 0.002, 3.0)),
    "low-sun-left": _preset((0.3, 0.78, 0.002, 3.0)),
    "low-sun-right": _preset((0.7, 0.78, 0.002, 3.0)),
    "overcast": _preset(
        (0.5, 0.0, 0.1, 1.0),
        (0.0, 0.45, 0.1, 0.8),
        (0.25, 0.45, 0.1, 0.8),
        (0.5, 0.45, 0.1, 0.8),
        (0.75, 0.45, 0.1, 0.8),
    ),
    "softbox": _preset((0.38, 0.45, 0.02, 2.0)),
    "two-lights": _preset((0.35, 0.4, 0.006, 2.0), (0.68, 0.55, 0.01, 1.0)),
    "rim-light": _preset((0.5, 0.6, 0.004, 2.5), (0.1, 0.3, 0.05, 0.4)),
}
DEFAULT_PRESET = "softbox"


def preset(name: str) -> LightMap:
    """A fresh light map for a named preset."""
    try:
        return PRESETS[name]()
    except KeyError:
        raise LightMapError(f"unknown preset {name!r}; choose one of: {', '.join(PRESETS)}") from None
