"""The camera a host remembers with one image (stdlib only): whether the image's horizon is given, its row and the
field of view, stored with that image (GIMP: an image parasite) so that no other image inherits it.

The record is compact JSON::

    {"format": "ssn-shadow-camera", "version": 1, "given": true, "horizon": 380.0, "fov": 45.0, "height": 480}

``height`` is the image's height when the record was written: an image scaled since gets the row scaled with it
(row 380 of a 480-row image is row 2375 once the image is scaled to 3000 rows). A record that is not one (another
program's, a damaged one) is no record: the image then starts as one never shadowed.
"""

from __future__ import annotations

import json
import math
from typing import Any

from .camera_rules import DEFAULT_FOV, EDITOR_FOV_RANGE, EDITOR_HORIZON_RANGE, within

__all__ = ["FORMAT", "NOT_GIVEN", "camera_record", "recalled_camera"]

FORMAT = "ssn-shadow-camera"
VERSION = 1
NOT_GIVEN: dict[str, Any] = {"given": False, "horizon": 0.0, "fov": DEFAULT_FOV}  # an image with no record


def camera_record(given: bool, horizon: float, fov: float, image_height: int) -> str:
    """The record of an image's camera settings (the horizon option ``given``, its ``horizon`` row and ``fov``)
    for an image ``image_height`` rows tall.

    Parameters
    ----------
    given : bool
        Whether the image's horizon is given (the option is ticked).
    horizon, fov : float
        The horizon row (canvas pixels from the top) and the vertical field of view in degrees.
    image_height : int
        The image's height in pixels now.

    Returns
    -------
    str
        Compact JSON, at most a few dozen bytes.
    """
    record = {
        "format": FORMAT,
        "version": VERSION,
        "given": bool(given),
        "horizon": float(horizon),
        "fov": float(fov),
        "height": int(image_height),
    }
    return json.dumps(record, separators=(",", ":"))


def recalled_camera(text: str | None, image_height: int) -> dict[str, Any]:
    """The camera settings a record (:func:`camera_record`) gives an image now ``image_height`` rows tall.

    Parameters
    ----------
    text : str or None
        The record stored with the image, or None where it has none.
    image_height : int
        The image's height in pixels now.

    Returns
    -------
    dict
        ``{"given": bool, "horizon": row, "fov": degrees}``: the row scaled by the change of the image's height
        and rounded to a whole row, both within the editors' bounds; :data:`NOT_GIVEN` for no record, or for text
        that is no valid record.
    """
    record = _parsed(text)
    if record is None:
        return dict(NOT_GIVEN)
    horizon = record["horizon"] * image_height / record["height"] if image_height > 0 else record["horizon"]
    return {
        "given": record["given"],
        "horizon": within(round(horizon), EDITOR_HORIZON_RANGE),
        "fov": within(record["fov"], EDITOR_FOV_RANGE),
    }


def _parsed(text: str | None) -> dict[str, Any] | None:
    if not text:
        return None
    try:
        record = json.loads(text)
    except ValueError:
        return None
    if not isinstance(record, dict) or record.get("format") != FORMAT or record.get("version") != VERSION:
        return None
    given, height = record.get("given"), record.get("height")
    numbers = [record.get("horizon"), record.get("fov"), height]
    if not isinstance(given, bool) or not all(_finite(n) for n in numbers) or not isinstance(height, int):
        return None
    return record if height > 0 else None


def _finite(value: object) -> bool:
    return isinstance(value, (int, float)) and not isinstance(value, bool) and math.isfinite(value)
