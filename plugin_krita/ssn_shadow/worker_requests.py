"""The worker's requests, built from the model's settings and the source (what is sent, not when)."""

from __future__ import annotations

from typing import Any

from .adapters.krita_document import Source
from .adapters.pixel_format import blend_mode, shadow_color
from .model import ShadowModel
from .shared import camera_rules, protocol

__all__ = ["preview", "render", "set_cutout", "set_geometry"]


def set_cutout(source: Source, camera: dict | None) -> tuple[dict[str, Any], dict[str, protocol.Buffer]]:
    """``set_cutout``: the source's canvas-sized alpha, the layer's opacity where it is below 1 (the alpha does
    not carry it), and the given camera if there is one."""
    alpha = protocol.Buffer(source.dtype, (source.height, source.width), source.alpha)
    params: dict[str, Any] = {"camera": camera} if camera else {}
    if source.opacity < 1.0:
        params["layer_opacity"] = source.opacity
    return params, {"alpha": alpha}


def set_geometry(model: ShadowModel, cutout: str) -> dict[str, Any]:
    """``set_geometry``: the model's lift (canvas rows) and thickness (None: read from the outline); the alpha is
    not sent again."""
    return {"cutout": cutout, "lift": float(model.lift), "thickness": model.thickness}


def render(model: ShadowModel, cutout: str, source: Source) -> tuple[dict[str, Any], str]:
    """``render`` in the document's pixel format and colour profile, and the layer's blend mode for its colour."""
    params = {
        "cutout": cutout,
        "light_map": model.light_map.to_dict(),
        "color": shadow_color(model.color, source.profile),
        "opacity": model.opacity,
        "format": source.layer_format.render_format(),
    }
    return params, blend_mode(model.color)


def preview(
    model: ShadowModel, cutout: str, source: Source, background: tuple[int, int, bytes]
) -> tuple[dict[str, Any], dict[str, protocol.Buffer]]:
    """``preview``: the shadow multiplied onto ``background`` (width, height, 8-bit RGBA), the thumbnail of a
    light drag; the given horizon scaled to it, or else the horizon the model read, dotted."""
    width, height, rgba = background
    params: dict[str, Any] = {
        "cutout": cutout,
        "light_map": model.light_map.to_dict(),
        "color": list(model.color),  # the thumbnail is 8-bit sRGB, whatever the document's profile
        "opacity": model.opacity,
    }
    camera = model.camera
    if camera:
        params["horizon"] = camera_rules.scaled_camera(camera, width / source.width)["horizon"]
    else:
        params["read_horizon"] = True
    return params, {"background": protocol.Buffer("uint8", (height, width, 4), rgba)}
