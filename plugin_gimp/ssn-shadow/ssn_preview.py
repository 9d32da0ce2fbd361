"""The dialog's preview, toolkit-free: a thumbnail of the image with the shadow the engine multiplies on.

The image's cutout is uploaded once, at the image's size; the worker's
``preview`` command casts its shadow on the thumbnail through the cutout's
framing scaled to it (as the Krita docker's live preview does), composites it
as GIMP's Multiply layer would, hides it where the cutout covers the image,
and draws the horizon; the plug-in only shows the bytes.
"""

from __future__ import annotations

from dataclasses import dataclass

from ssn_core import Engine, ShadowError, engine_call
from ssn_engine_link import protocol
from ssn_settings import ShadowSettings

PREVIEW_SIZE = 384  # the thumbnail's longer side at most
PREVIEW_HEIGHT = 288  # and its height at most: the dialog of a portrait image fits a 1366 x 768 screen


@dataclass(frozen=True)
class Thumbnail:
    """The image's composite, 8-bit RGB or RGBA, rows packed."""

    width: int
    height: int
    channels: int
    data: bytes


def render_preview(
    engine: Engine,
    cutout_id: str,
    settings: ShadowSettings,
    thumbnail: Thumbnail,
    horizon: float | None = None,
) -> tuple[bytes, str]:
    """The thumbnail with the shadow multiplied on (packed RGB, the thumbnail's size) and why no shadow shows
    ("" when one does). ``horizon``, a thumbnail row, is drawn, and without it the horizon the model read from the
    cutout's outline (dotted)."""
    edits = settings.ao_edits()
    if edits:
        engine_call(engine, "edit_ao", cutout=cutout_id, edits=edits)
    w, h = thumbnail.width, thumbnail.height
    buffers = {"background": protocol.Buffer("uint8", (h, w, thumbnail.channels), thumbnail.data)}
    params = settings.render_params("uint8", (w, h))
    params = {key: params[key] for key in ("light_map", "preset", "color", "opacity") if key in params}
    if horizon is not None:
        params["horizon"] = horizon
    else:
        params["read_horizon"] = True
    reply, out = engine_call(engine, "preview", buffers, cutout=cutout_id, **params)
    image = out.get("image")
    if image is None or image.dtype != "uint8" or tuple(image.shape) != (h, w, 3):
        raise ShadowError("The shadow engine sent a malformed preview.")
    return bytes(memoryview(image.data).cast("B")), str(reply.get("no_shadow") or "")


HANDLE_SLACK = 8  # thumbnail pixels: how far beside the cutout's columns (and above its lowest row) a drag lifts it
GROUND_MARK = (230, 0, 180)  # the ground point's mark: a colour the horizon lines (orange, blue) do not use


def in_lift_handle(x: float, y: float, scale: float, bbox: tuple[int, int, int, int] | list[int], row: int) -> bool:
    """Whether a press at thumbnail point (``x``, ``y``) grabs the lift handle: under the cutout (at or below the
    canvas row ``row`` its lift counts from, the worker's ``lift_row``, less :data:`HANDLE_SLACK`) and within its
    columns (its ``bbox``'s, :data:`HANDLE_SLACK` wider each side)."""
    x0, x1 = bbox[0] * scale - HANDLE_SLACK, bbox[2] * scale + HANDLE_SLACK
    return x0 <= x <= x1 and y >= row * scale - HANDLE_SLACK


def lift_from_preview(y: float, scale: float, row: int) -> float:
    """The lift (whole canvas rows) that puts the ground point beneath the cutout at thumbnail row ``y`` of a
    preview drawn at ``scale``: canvas rows = preview rows / scale, less the row ``row`` its lift counts from, at
    least 0."""
    return float(max(0, round(y / scale) - row))


def draw_ground_mark(
    rgb: bytes, size: tuple[int, int], scale: float, bbox: tuple[int, int, int, int] | list[int], row: int, lift: float
) -> bytes:
    """``rgb`` (packed RGB, ``size`` = (width, height)) with the lift handle drawn: a short bar across the cutout's
    middle column (of its ``bbox``) at the ground point (the row ``row`` its lift counts from plus ``lift``, at
    ``scale``), and, lifted, a dotted line up from it to that row; what lies off the thumbnail is not drawn."""
    w, h = size
    out = bytearray(rgb)
    centre = round((bbox[0] + bbox[2]) / 2 * scale)
    top = round(row * scale)
    ground = round((row + lift) * scale)

    def put(x: int, y: int) -> None:
        if 0 <= x < w and 0 <= y < h:
            out[3 * (y * w + x) : 3 * (y * w + x) + 3] = bytes(GROUND_MARK)

    for y in range(top + 1, ground):
        if (y - top) % 3 == 0:
            put(centre, y)
    for dy in (0, 1):
        for x in range(centre - HANDLE_SLACK, centre + HANDLE_SLACK + 1):
            put(x, ground + dy)
    return bytes(out)
