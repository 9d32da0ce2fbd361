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
