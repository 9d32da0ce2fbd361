"""The GIMP side of the run logic: reads the cutout and writes the shadow layer via Gegl buffers.

Implements :class:`ssn_core.Host` for one image and drawable. Pixels cross
only through ``Gegl.Buffer.get``/``set`` with the explicit babl formats of
:mod:`ssn_pixels`.
"""

from __future__ import annotations

from typing import Any

import gi

gi.require_version("Gimp", "3.0")
gi.require_version("Gegl", "0.4")
gi.require_version("Babl", "0.1")
from gi.repository import Babl, Gegl, Gimp  # noqa: E402

from ssn_core import Cutout, ShadowError, ShadowLayerData  # noqa: E402
from ssn_pixels import PixelFormatError, PixelPlan, layer_image_type, plan_for_precision  # noqa: E402
from ssn_preview import Thumbnail  # noqa: E402
from ssn_settings import ARGUMENTS  # noqa: E402


def config_values(config: Gimp.ProcedureConfig) -> dict:
    """Procedure argument values by name; the colour as sRGB (perceptual) components in 0..1."""
    values = {}
    for spec in ARGUMENTS:
        value = config.get_property(spec.name)
        if spec.kind == "color":
            rgba = value.get_rgba_with_space(Babl.space("sRGB"))
            value = tuple(min(max(c, 0.0), 1.0) for c in (rgba.red, rgba.green, rgba.blue))
        values[spec.name] = value
    return values


def no_cutout_message(layer_name: str) -> str:
    return (
        f'Nothing to cast a shadow from: the selection is empty and the layer "{layer_name}" has no '
        "alpha channel. Select the object (for example with Select > By Color or the Foreground "
        "Select tool), or add an alpha channel (Layer > Transparency > Add Alpha Channel) and erase "
        "the background."
    )


class GimpHost:
    """One image and its active drawable, as the run logic sees them."""

    def __init__(self, image: Gimp.Image, drawable: Gimp.Drawable) -> None:
        if not isinstance(drawable, Gimp.Layer) or isinstance(drawable, Gimp.LayerMask):
            raise ShadowError("Soft Shadow works on a layer: select a layer, not a channel or a mask.")
        self.image, self.drawable = image, drawable
        group = drawable.get_parent()
        while group is not None:  # the shadow layer goes beside the drawable: its group must take it
            if group.get_lock_content():
                raise ShadowError(
                    f'The layer is inside the group "{group.get_name()}", whose contents are locked, so the '
                    "shadow layer cannot be added beside it. Unlock the group's contents (Layers dialog, the "
                    "lock icon) or move the layer out of the group."
                )
            group = group.get_parent()

    def pixel_plan(self) -> PixelPlan:
        try:
            layer_image_type(self.image.get_base_type().value_nick)  # rejects indexed images with a message
            return plan_for_precision(self.image.get_precision().value_nick)
        except PixelFormatError as exc:
            raise ShadowError(str(exc)) from None

    def source_name(self) -> str:
        return self.drawable.get_name()

    def read_cutout(self, plan: PixelPlan) -> Cutout:
        """The selection if there is one, else the layer's alpha, as a canvas-sized buffer."""
        width, height = self.image.get_width(), self.image.get_height()
        _, non_empty, *_ = Gimp.Selection.bounds(self.image)
        if non_empty:
            buffer = self.image.get_selection().get_buffer()
            rect = Gegl.Rectangle.new(0, 0, width, height)
            data = buffer.get(rect, 1.0, plan.selection_format, Gegl.AbyssPolicy.NONE)
            return Cutout(width, height, plan.alpha_dtype, bytes(data), "the selection")
        if not self.drawable.has_alpha():
            raise ShadowError(no_cutout_message(self.drawable.get_name()))
        _, off_x, off_y = self.drawable.get_offsets()
        # The canvas rectangle in the layer's coordinates; outside the layer the abyss is transparent.
        rect = Gegl.Rectangle.new(-off_x, -off_y, width, height)
        data = self._visible_alpha().get(rect, 1.0, plan.layer_alpha_format, Gegl.AbyssPolicy.NONE)
        return Cutout(width, height, plan.alpha_dtype, bytes(data), f'the layer "{self.drawable.get_name()}"')

    def _visible_alpha(self) -> Gegl.Buffer:
        """The layer's pixels as they show: with an active layer mask, multiplied by it (a GEGL graph, so the
        user's layer and mask are only read)."""
        buffer = self.drawable.get_buffer()
        mask = self.drawable.get_mask()
        if mask is None or not self.drawable.get_apply_mask():
            return buffer
        graph = Gegl.Node()
        source = graph.create_child("gegl:buffer-source")
        source.set_property("buffer", buffer)
        aux = graph.create_child("gegl:buffer-source")
        aux.set_property("buffer", mask.get_buffer())
        masked = graph.create_child("gegl:opacity")
        source.connect_to("output", masked, "input")
        aux.connect_to("output", masked, "aux")
        extent = buffer.get_extent()
        out = Gegl.Buffer.new("RGBA float", extent.x, extent.y, extent.width, extent.height)
        sink = graph.create_child("gegl:write-buffer")
        sink.set_property("buffer", out)
        masked.connect_to("output", sink, "input")
        sink.process()
        return out

    def thumbnail(self, width: int, height: int) -> Thumbnail:
        """The image's composite, 8-bit sRGB, at most ``width`` x ``height``."""
        pixbuf = self.image.get_thumbnail(width, height, Gimp.PixbufTransparency.SMALL_CHECKS)
        if pixbuf is None:
            # GIMP makes no thumbnail at some precisions (16/32-bit integer, half, float, double): take it
            # from a small 8-bit copy of the image, deleted at once (the user's image is only read).
            copy = self.image.duplicate()
            try:
                copy.scale(width, height)
                copy.convert_precision(Gimp.Precision.U8_NON_LINEAR)
                pixbuf = copy.get_thumbnail(width, height, Gimp.PixbufTransparency.SMALL_CHECKS)
            finally:
                copy.delete()
            if pixbuf is None:
                raise ShadowError("GIMP could not make a preview of this image; run the filter without the dialog.")
        w, h, channels, stride = (
            pixbuf.get_width(),
            pixbuf.get_height(),
            pixbuf.get_n_channels(),
            pixbuf.get_rowstride(),
        )
        pixels = pixbuf.get_pixels()
        packed = (
            pixels
            if stride == w * channels
            else b"".join(pixels[y * stride : y * stride + w * channels] for y in range(h))
        )
        return Thumbnail(w, h, channels, bytes(packed[: w * h * channels]))

    def undo_group_start(self) -> None:
        self.image.undo_group_start()

    def undo_group_end(self) -> None:
        self.image.undo_group_end()

    def add_shadow_layer(self, name: str, shadow: ShadowLayerData, plan: PixelPlan) -> Any:
        """A Multiply layer right below the drawable, at the shadow's place on the canvas."""
        image_type = getattr(Gimp.ImageType, layer_image_type(self.image.get_base_type().value_nick))
        layer = Gimp.Layer.new(
            self.image, name, shadow.width, shadow.height, image_type, 100.0, Gimp.LayerMode.MULTIPLY
        )
        parent = self.drawable.get_parent()
        position = self.image.get_item_position(self.drawable) + 1
        self.image.insert_layer(layer, parent, position)
        layer.set_offsets(shadow.x, shadow.y)
        buffer = layer.get_buffer()
        buffer.set(Gegl.Rectangle.new(0, 0, shadow.width, shadow.height), plan.shadow_format, shadow.data)
        buffer.flush()
        layer.update(0, 0, shadow.width, shadow.height)
        return layer
