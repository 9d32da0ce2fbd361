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

from ssn_core import Cutout, ShadowError, ShadowLayerData, target_note  # noqa: E402
from ssn_pixels import PixelFormatError, PixelPlan, layer_image_type, plan_for_precision  # noqa: E402
from ssn_preview import Thumbnail  # noqa: E402
from ssn_settings import (  # noqa: E402
    ARGUMENTS,
    image_camera_arguments,
    image_camera_record,
    image_geometry_arguments,
    image_geometry_record,
)

SOURCE_PARASITE = "ssn-shadow-source"  # on a shadow layer: the tattoo of the layer it was cast from
CAMERA_PARASITE = "ssn-shadow-camera"  # on an image: its camera settings (ssn_engine_link.image_camera)
GEOMETRY_PARASITE = "ssn-shadow-geometry"  # on an image: its lift and thickness (image_geometry_record)


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


def _siblings(image: Gimp.Image, layer: Gimp.Layer) -> list:
    parent = layer.get_parent()
    return list(parent.get_children() if parent is not None else image.get_layers())


def _source_tattoo(layer: Gimp.Layer) -> int | None:
    """The tattoo of the layer a shadow layer was cast from (its parasite), or None for other layers."""
    parasite = layer.get_parasite(SOURCE_PARASITE)
    if parasite is None:
        return None
    try:
        return int(bytes(parasite.get_data()).decode("ascii"))
    except (UnicodeDecodeError, ValueError):
        return None


class GimpHost:
    """One image and its active drawable, as the run logic sees them.

    The source is the active layer, or, when the active layer is a shadow this filter made, the layer that
    shadow was cast from: running the filter again (Ctrl+F) re-casts the source's shadow instead of shadowing
    the shadow. The layer's existing shadow, if any, is replaced in its place (:meth:`add_shadow_layer`).
    """

    def __init__(self, image: Gimp.Image, drawable: Gimp.Drawable) -> None:
        if not isinstance(drawable, Gimp.Layer) or isinstance(drawable, Gimp.LayerMask):
            raise ShadowError("Soft Shadow works on a layer: select a layer, not a channel or a mask.")
        self.image, self.active = image, drawable
        source = self._source_of(drawable)
        self.drawable = source if source is not None else drawable
        self.replacing = drawable if source is not None else self._shadow_of(self.drawable)
        group = self.drawable.get_parent()
        while group is not None:  # the shadow layer goes beside the drawable: its group must take it
            if group.get_lock_content():
                raise ShadowError(
                    f'The layer is inside the group "{group.get_name()}", whose contents are locked, so the '
                    "shadow layer cannot be added beside it. Unlock the group's contents (Layers dialog, the "
                    "lock icon) or move the layer out of the group."
                )
            group = group.get_parent()

    def _source_of(self, layer: Gimp.Layer) -> Gimp.Layer | None:
        """The layer a shadow layer was cast from, or None when ``layer`` is no shadow of this filter. Only the
        filter's parasite makes a shadow: a layer of the user's named "Shadow: X", even right below "X", is the
        user's, and is cast from (and kept) like any other layer."""
        tattoo = _source_tattoo(layer)
        if tattoo is None:
            return None
        source = self.image.get_layer_by_tattoo(tattoo)
        if source is None:
            raise ShadowError(
                f'"{layer.get_name()}" is a shadow whose layer is no longer in the image: select the layer '
                "to cast a shadow from."
            )
        return source

    def _shadow_of(self, source: Gimp.Layer) -> Gimp.Layer | None:
        """The shadow layer this filter cast from ``source`` earlier (its parasite names ``source``), if it is still
        beside it. Never a layer by its name alone: a re-run replaces (deletes) the layer it finds."""
        tattoo = source.get_tattoo()
        return next((lay for lay in _siblings(self.image, source) if _source_tattoo(lay) == tattoo), None)

    def target_note(self) -> str:
        """What the filter casts (the selection, with its size, or the layer) and which shadow it replaces, for
        the dialog: the choice :meth:`read_cutout` makes."""
        replacing = self.replacing.get_name() if self.replacing is not None else None
        bounds = self.selection_bounds()
        return target_note(self.drawable.get_name(), replacing, (bounds[2], bounds[3]) if bounds else None)

    def selection_bounds(self) -> tuple[int, int, int, int] | None:
        """The selection's bounds on the canvas (x, y, width, height), or None when nothing is selected: then
        the filter casts the layer's alpha, else the selection."""
        _, non_empty, x1, y1, x2, y2 = Gimp.Selection.bounds(self.image)
        return (x1, y1, x2 - x1, y2 - y1) if non_empty else None

    def horizontal_guides(self) -> list[float]:
        """The image's horizontal guides (canvas rows), in GIMP's order."""
        rows, guide = [], self.image.find_next_guide(0)
        while guide:
            if self.image.get_guide_orientation(guide) == Gimp.OrientationType.HORIZONTAL:
                rows.append(float(self.image.get_guide_position(guide)))
            guide = self.image.find_next_guide(guide)
        return rows

    def image_camera(self) -> dict[str, Any]:
        """The camera arguments this image had when the filter last ran on it interactively (scaled with the image
        since), or the horizon not given: never another image's (GIMP's last values are global)."""
        return image_camera_arguments(self._image_record(CAMERA_PARASITE), self.image.get_height())

    def remember_camera(self, values: dict[str, Any]) -> None:
        """Keep the camera arguments in ``values`` with the image (saved in the XCF; no undo step)."""
        self._keep_image_record(CAMERA_PARASITE, image_camera_record(values, self.image.get_height()))

    def image_geometry(self) -> dict[str, float]:
        """The lift and thickness arguments this image had when the filter last ran on it interactively (the lift
        scaled with the image since), or the defaults (resting on the ground, the thickness read): never another
        image's."""
        return image_geometry_arguments(self._image_record(GEOMETRY_PARASITE), self.image.get_height())

    def remember_geometry(self, values: dict[str, Any]) -> None:
        """Keep the lift and thickness arguments in ``values`` with the image (saved in the XCF; no undo step)."""
        self._keep_image_record(GEOMETRY_PARASITE, image_geometry_record(values, self.image.get_height()))

    def _image_record(self, name: str) -> str | None:
        """The text of the image's parasite ``name``, or None where it has none."""
        parasite = self.image.get_parasite(name)
        return bytes(parasite.get_data()).decode("utf-8", "replace") if parasite is not None else None

    def _keep_image_record(self, name: str, record: str) -> None:
        """Attach ``record`` (ASCII) to the image as its persistent parasite ``name``, replacing one before."""
        self.image.attach_parasite(Gimp.Parasite.new(name, Gimp.PARASITE_PERSISTENT, list(record.encode("ascii"))))

    def hidden_reason(self) -> str | None:
        """Why the source layer shows nothing (hidden, or at opacity 0), or None; a selection casts regardless."""
        if self.selection_bounds() is not None:
            return None
        name = self.drawable.get_name()
        item = self.drawable
        while item is not None:
            if not item.get_visible():
                where = "is hidden" if item is self.drawable else f'is in the hidden group "{item.get_name()}"'
                return (
                    f'The layer "{name}" {where}, so it shows nothing to cast a shadow from. Make it visible '
                    "(the eye in the Layers dialog), or select the object to cast from."
                )
            item = item.get_parent()
        if self.drawable.get_opacity() <= 0.0:
            return (
                f'The layer "{name}" is at opacity 0, so it shows nothing to cast a shadow from. Raise its '
                "opacity (Layers dialog), or select the object to cast from."
            )
        return None

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
        if self.selection_bounds() is not None:
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

    def shown_opacity(self) -> float:
        """The layer's opacity times its groups' (0..1): how strongly its pixels show."""
        opacity, item = 1.0, self.drawable
        while item is not None:
            opacity *= min(max(item.get_opacity() / 100.0, 0.0), 1.0)
            item = item.get_parent()
        return opacity

    def _visible_alpha(self) -> Gegl.Buffer:
        """The layer's pixels as they show: their alpha times the layer's opacity (and its groups'; a 50 % layer
        casts a shadow half as dark) and, with an active layer mask, times the mask (a GEGL graph, so the user's
        layer and mask are only read)."""
        buffer = self.drawable.get_buffer()
        mask = self.drawable.get_mask()
        masked = mask is not None and self.drawable.get_apply_mask()
        opacity = self.shown_opacity()
        if not masked and opacity >= 1.0:
            return buffer
        graph = Gegl.Node()
        source = graph.create_child("gegl:buffer-source")
        source.set_property("buffer", buffer)
        shown = graph.create_child("gegl:opacity")  # input x aux (if connected) x value
        shown.set_property("value", opacity)
        source.connect_to("output", shown, "input")
        if mask is not None and masked:
            aux = graph.create_child("gegl:buffer-source")
            aux.set_property("buffer", mask.get_buffer())
            aux.connect_to("output", shown, "aux")
        extent = buffer.get_extent()
        out = Gegl.Buffer.new("RGBA float", extent.x, extent.y, extent.width, extent.height)
        sink = graph.create_child("gegl:write-buffer")
        sink.set_property("buffer", out)
        shown.connect_to("output", sink, "input")
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
        """A Multiply layer right below the drawable, at the shadow's place on the canvas; or, where the layer
        has a shadow already, the new one in its place (keeping its name, visibility, opacity and mode). The
        layer that was active stays active (the new shadow, where the old one was)."""
        image_type = getattr(Gimp.ImageType, layer_image_type(self.image.get_base_type().value_nick))
        old = self.replacing
        opacity, mode = (old.get_opacity(), old.get_mode()) if old is not None else (100.0, Gimp.LayerMode.MULTIPLY)
        layer = Gimp.Layer.new(self.image, name, shadow.width, shadow.height, image_type, opacity, mode)
        anchor = old if old is not None else self.drawable
        position = self.image.get_item_position(anchor) + (0 if old is not None else 1)
        self.image.insert_layer(layer, anchor.get_parent(), position)
        layer.attach_parasite(
            Gimp.Parasite.new(
                SOURCE_PARASITE,
                Gimp.PARASITE_PERSISTENT | Gimp.PARASITE_UNDOABLE,
                list(str(self.drawable.get_tattoo()).encode("ascii")),
            )
        )
        layer.set_offsets(shadow.x, shadow.y)
        buffer = layer.get_buffer()
        buffer.set(Gegl.Rectangle.new(0, 0, shadow.width, shadow.height), plan.shadow_format, shadow.data)
        buffer.flush()
        layer.update(0, 0, shadow.width, shadow.height)
        if old is not None:
            layer.set_visible(old.get_visible())
            kept_name = old.get_name()  # the user may have renamed it; set once the old layer has gone
            self.image.remove_layer(old)
            layer.set_name(kept_name)
            self.replacing = layer
        active = layer if self.active is old else self.active
        self.image.set_selected_layers([active])
        return layer
