"""Environment light maps as editable lists of lights: 2D Gaussians and uniform disks.

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

A light with an ``angle`` is instead a uniform disk of that apparent diameter
(degrees) centred in the direction of (u, v) (conventions, "Light size"). Its
power (solid-angle integral of radiance) is that of a Gaussian of the same
intensity and softness ``REFERENCE_SOFTNESS`` at the same place, so resizing
a disk does not make it brighter or dimmer. Such a light keeps a ``softness``
too, the Gaussian a reader that knows no ``angle`` uses (:func:`angle_softness`).
"""

from __future__ import annotations

import json
import math
import random
from collections.abc import Callable, Iterator
from dataclasses import dataclass, field, replace
from typing import Any

from .protocol import NestingError, checked_number, loads, versioned

FORMAT = "ssn-shadow-elm"
VERSION = 1

# Table 1 of the paper.
MAX_LIGHTS = 50
INTENSITY_RANGE = (0.0, 3.0)
SOFTNESS_RANGE = (1e-4, 0.1)
ANGLE_RANGE = (0.1, 40.0)  # a disk light's apparent diameter, degrees: from below the sun's to a large softbox
REFERENCE_SOFTNESS = 0.01  # a disk light carries the power of a Gaussian of its intensity and this softness
ASPECT = 2.0  # map width / height


class LightMapError(ValueError):
    """Invalid light-map data; the message names the offending field."""


def _number(value: Any, name: str, lo: float, hi: float) -> float:
    return checked_number(value, name, lo, hi, LightMapError)


def angle_softness(angle: float) -> float:
    """The softness (sigma^2, map heights squared) of the Gaussian as wide as a disk of diameter ``angle``
    degrees: the disk's standard deviation across, (angle / 4) degrees, in map heights of 90 degrees; clamped to
    ``SOFTNESS_RANGE``."""
    return min(max((angle / 4.0 / 90.0) ** 2, SOFTNESS_RANGE[0]), SOFTNESS_RANGE[1])


def softness_angle(softness: float) -> float:
    """The apparent diameter in degrees of the disk as wide as a Gaussian of ``softness`` (the inverse of
    :func:`angle_softness`, unclamped)."""
    return 4.0 * 90.0 * math.sqrt(softness)


@dataclass(frozen=True)
class GaussianLight:
    """One light: position (u, v), softness sigma^2 and peak intensity; with ``angle`` (degrees) a uniform disk
    of that apparent diameter instead, of the power of a Gaussian of the same intensity and softness
    ``REFERENCE_SOFTNESS``."""

    u: float
    v: float
    softness: float = 0.01
    intensity: float = 1.0
    angle: float | None = None

    def __post_init__(self) -> None:
        object.__setattr__(self, "u", _number(self.u, "u", 0.0, 1.0))
        object.__setattr__(self, "v", _number(self.v, "v", 0.0, 1.0))
        object.__setattr__(self, "softness", _number(self.softness, "softness", *SOFTNESS_RANGE))
        object.__setattr__(self, "intensity", _number(self.intensity, "intensity", *INTENSITY_RANGE))
        if self.angle is not None:
            object.__setattr__(self, "angle", _number(self.angle, "angle", *ANGLE_RANGE))

    @classmethod
    def disk(cls, u: float, v: float, angle: float, intensity: float = 1.0) -> GaussianLight:
        """A disk light of diameter ``angle`` degrees, its ``softness`` the Gaussian as wide (for readers that
        know no ``angle``)."""
        return cls(u, v, angle_softness(_number(angle, "angle", *ANGLE_RANGE)), intensity, angle)

    @property
    def size_degrees(self) -> float:
        """The apparent diameter in degrees: the disk's ``angle``, or the Gaussian's equivalent
        (:func:`softness_angle`)."""
        return self.angle if self.angle is not None else softness_angle(self.softness)

    @property
    def radius(self) -> float:
        """The Gaussian's standard deviation, or the disk's radius, in map heights."""
        return math.sqrt(self.softness) if self.angle is None else self.angle / 2.0 / 90.0

    def distance_to(self, u: float, v: float) -> float:
        """Distance in map heights from the light's centre, azimuth wrapping."""
        du = abs(u - self.u) % 1.0
        du = min(du, 1.0 - du)
        return math.hypot(ASPECT * du, v - self.v)

    def to_dict(self) -> dict[str, float]:
        out = {"u": self.u, "v": self.v, "softness": self.softness, "intensity": self.intensity}
        if self.angle is not None:
            out["angle"] = self.angle
        return out

    @classmethod
    def from_dict(cls, item: dict[str, Any]) -> GaussianLight:
        """A light from its JSON object: ``u``, ``v``, ``intensity`` and ``softness`` or ``angle`` or both (then
        ``angle`` rules). Errors name the field."""
        required = {"u", "v", "intensity"} | (set() if "angle" in item else {"softness"})
        missing = required - set(item)
        if missing:
            raise LightMapError(f"{sorted(missing)[0]}: missing (a light needs u, v, intensity and softness or angle)")
        if "softness" in item:
            return cls(item["u"], item["v"], item["softness"], item["intensity"], item.get("angle"))
        return cls.disk(item["u"], item["v"], item["angle"], item["intensity"])

    @property
    def power(self) -> float:
        """The solid-angle integral of the light's radiance over the sky (steradians times intensity)."""
        softness = self.softness if self.angle is None else REFERENCE_SOFTNESS
        return self.intensity * gaussian_power(self.v, softness)


def gaussian_power(v: float, softness: float) -> float:
    """The solid-angle integral of a Gaussian light of peak 1 and ``softness`` at map row ``v``: across, the
    Gaussian's integral (the azimuth wraps, so all of it); down, a midpoint sum of it times cos(elevation) over
    the map's rows (the map spans pi radians of azimuth and pi / 2 of elevation per map height)."""
    sigma = math.sqrt(softness)
    across = math.sqrt(2.0 * math.pi) * sigma
    steps = 400
    down = 0.0
    for k in range(steps):
        y = (k + 0.5) / steps
        down += math.exp(-((y - v) ** 2) / (2.0 * softness)) * math.sin(math.pi / 2.0 * y) / steps
    return across * down * math.pi * math.pi / 2.0


def _disk_frame(light: GaussianLight) -> tuple[tuple[float, ...], tuple[float, ...], tuple[float, ...]]:
    """A disk light's centre direction and two unit vectors across it (horizontal, and up the sky), as (x, y, z)
    with y up."""
    e, a = math.pi / 2.0 * (1.0 - light.v), 2.0 * math.pi * light.u - math.pi
    centre = (math.cos(e) * math.sin(a), math.sin(e), math.cos(e) * math.cos(a))
    east = (math.cos(a), 0.0, -math.sin(a))
    north = (-math.sin(e) * math.sin(a), math.cos(e), -math.sin(e) * math.cos(a))
    return centre, east, north


def _off_centre(light: GaussianLight, theta: float, phi: float) -> list[float]:
    """The direction ``theta`` radians from a disk light's centre, at ``phi`` around it."""
    centre, east, north = _disk_frame(light)
    ct, st = math.cos(theta), math.sin(theta)
    return [ct * c + st * (math.cos(phi) * x + math.sin(phi) * y) for c, x, y in zip(centre, east, north, strict=True)]


def _map_point(d: list[float]) -> tuple[float, float]:
    """Map coordinates (u in [0, 1), v) of a direction; below the horizon v exceeds 1."""
    elevation = math.asin(max(-1.0, min(1.0, d[1])))
    azimuth = math.atan2(d[0], d[2])
    return (azimuth + math.pi) / (2.0 * math.pi) % 1.0, 1.0 - elevation / (math.pi / 2.0)


def disk_directions(light: GaussianLight, count: int) -> list[tuple[float, float, float]]:
    """About ``count`` directions spread evenly over a disk light's solid angle, as (u, v, share): map
    coordinates and the share of the disk's power each carries (the shares sum to the part of the disk above
    the horizon; directions below it are left out: they light no ground). Concentric rings of equal-area cells."""
    if light.angle is None:
        raise LightMapError("disk_directions: the light has no angle")
    rings = max(1, round(math.sqrt(count / 3.0)))
    cap = 1.0 - math.cos(math.radians(light.angle) / 2.0)
    total = 3 * rings * rings  # cells: ring k (0-based) holds 6 k + 3 of them, all of equal solid angle
    out = []
    for k in range(rings):
        cells = 6 * k + 3
        # the ring's middle, by solid angle: 1 - cos(theta) halfway between its edges' values
        theta = math.acos(1.0 - cap * (k * k + (k + 1) ** 2) / 2.0 / (rings * rings))
        for j in range(cells):
            d = _off_centre(light, theta, 2.0 * math.pi * (j + 0.5 * (k % 2)) / cells)
            if d[1] > 0.0:
                out.append((*_map_point(d), 1.0 / total))
    return out


def disk_rim(light: GaussianLight, count: int) -> list[tuple[float, float]]:
    """``count`` points (u, v) around a disk light's edge, its true outline on the map: wider across than down
    where it is high in the sky (a degree of azimuth is narrower there). ``u`` runs on from the light's own
    (it may leave [0, 1]: the map wraps), ``v`` exceeds 1 below the horizon."""
    if light.angle is None:
        raise LightMapError("disk_rim: the light has no angle")
    half = math.radians(light.angle) / 2.0
    out = []
    for k in range(count):
        u, v = _map_point(_off_centre(light, half, 2.0 * math.pi * k / count))
        out.append((light.u + (u - light.u + 0.5) % 1.0 - 0.5, v))
    return out


def disk_texel_means(light: GaussianLight, width: int, height: int, count: int) -> dict[tuple[int, int], float]:
    """A disk light's mean radiance in each texel of a width x height map that it reaches, {(row, col): value}:
    the power of its directions (:func:`disk_directions`) in the texel over the texel's solid angle."""
    out: dict[tuple[int, int], float] = {}
    for u, v, share in disk_directions(light, count):
        i, j = min(int(v * height), height - 1), min(int(u * width), width - 1)
        out[i, j] = out.get((i, j), 0.0) + share
    power = light.power
    for (i, j), share in out.items():
        band = math.sin(math.pi / 2.0 * (1.0 - i / height)) - math.sin(math.pi / 2.0 * (1.0 - (i + 1) / height))
        out[i, j] = power * share / (band * 2.0 * math.pi / width)
    return out


def disk_samples(angle: float, width: int) -> int:
    """How many directions a disk of ``angle`` degrees is drawn with on a map ``width`` texels across: about 4
    per texel of its area (at least 12)."""
    texel = 360.0 / width
    return max(12, round(4 * (angle / texel + 1.0) ** 2))


def _clamp(x: float, lo: float, hi: float) -> float:
    if not math.isfinite(x):
        raise LightMapError(f"expected a finite number, got {x!r}")
    return min(max(x, lo), hi)


@dataclass
class LightMap:
    """An editable list of Gaussian lights (the editor's model)."""

    lights: list[GaussianLight] = field(default_factory=list)

    # -- editing -----------------------------------------------------------
    def add(
        self, u: float, v: float, softness: float = 0.01, intensity: float = 1.0, angle: float | None = None
    ) -> int:
        """Add a light (position wrapped/clamped into the map; with ``angle`` a disk light of that diameter in
        degrees, clamped to ``ANGLE_RANGE``, its softness then the Gaussian as wide); return its index."""
        if len(self.lights) >= MAX_LIGHTS:
            raise LightMapError(f"lights: at most {MAX_LIGHTS} lights")
        u, v, intensity = _clamp(u, -1e9, 1e9) % 1.0, _clamp(v, 0.0, 1.0), _clamp(intensity, *INTENSITY_RANGE)
        if angle is None:
            self.lights.append(GaussianLight(u, v, _clamp(softness, *SOFTNESS_RANGE), intensity))
        else:
            self.lights.append(GaussianLight.disk(u, v, _clamp(angle, *ANGLE_RANGE), intensity))
        return len(self.lights) - 1

    def move(self, index: int, u: float, v: float) -> None:
        """Move a light; u wraps around the azimuth, v is clamped to the map."""
        self.lights[index] = replace(self.lights[index], u=_clamp(u, -1e9, 1e9) % 1.0, v=_clamp(v, 0.0, 1.0))

    def resize(self, index: int, softness: float) -> None:
        """Set a light's softness (sigma^2), clamped to Table 1's range; a disk light takes the diameter of the
        Gaussian as wide (:func:`softness_angle`)."""
        light = self.lights[index]
        if light.angle is not None:
            self.set_angle(index, softness_angle(_clamp(softness, *SOFTNESS_RANGE)))
            return
        self.lights[index] = replace(light, softness=_clamp(softness, *SOFTNESS_RANGE))

    def set_angle(self, index: int, angle: float) -> None:
        """Set a disk light's diameter in degrees, clamped to ``ANGLE_RANGE`` (its softness follows). Its power
        stays the same: a disk keeps its intensity; a Gaussian light becomes a disk of the intensity that carries
        its power (conventions, "Light size"), as far as ``INTENSITY_RANGE`` allows."""
        light = self.lights[index]
        intensity = light.intensity
        if light.angle is None:
            share = gaussian_power(light.v, light.softness) / gaussian_power(light.v, REFERENCE_SOFTNESS)
            intensity = _clamp(intensity * share, *INTENSITY_RANGE)
        self.lights[index] = GaussianLight.disk(light.u, light.v, _clamp(angle, *ANGLE_RANGE), intensity)

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
            try:
                parsed.append(GaussianLight.from_dict(item))
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


def _disk_preset(*lights: tuple[float, float, float, float]) -> Callable[[], LightMap]:
    return lambda: LightMap([GaussianLight.disk(*light) for light in lights])


SUN, HAZY_SUN, SOFTBOX = 0.53, 3.0, 16.0  # apparent diameters, degrees

# (u, v, softness, intensity), or for disk lights (u, v, angle in degrees, intensity). u = 0.5 is the sky
# behind the object (shadow towards the viewer); u < 0.5 is left of the view, so its shadow falls right.
PRESETS: dict[str, Callable[[], LightMap]] = {
    "sun": _disk_preset((0.35, 0.6, SUN, 3.0)),
    "hazy-sun": _disk_preset((0.35, 0.6, HAZY_SUN, 3.0)),
    "high-sun": _disk_preset((0.5, 0.12, SUN, 3.0)),
    "low-sun-left": _disk_preset((0.3, 0.78, SUN, 3.0)),
    "low-sun-right": _disk_preset((0.7, 0.78, SUN, 3.0)),
    "overcast": _preset(
        (0.5, 0.0, 0.1, 1.0),
        (0.0, 0.45, 0.1, 0.8),
        (0.25, 0.45, 0.1, 0.8),
        (0.5, 0.45, 0.1, 0.8),
        (0.75, 0.45, 0.1, 0.8),
    ),
    "softbox": _disk_preset((0.38, 0.45, SOFTBOX, 2.0)),
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
