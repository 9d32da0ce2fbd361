"""The filter's run logic, separated from GIMP so it is testable without it.

:func:`make_shadow` asks a :class:`Host` (the GIMP adapter, or a fake in
tests) for the cutout alpha, has the engine worker predict and composite the
shadow, then asks the host to add it as one layer inside one undo group. All
the engine work happens before the undo group opens, so a failure leaves the
image untouched. Every failure becomes :class:`ShadowError` with a message
for the user.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any, Protocol

from ssn_engine_link import client as engine_client
from ssn_engine_link import geometry_rules, protocol, shadow_notes
from ssn_pixels import BYTES_PER_SAMPLE, PixelPlan, is_blank
from ssn_settings import ARG_BY_NAME, LAYER_PREFIX, SettingsError, ShadowSettings


class ShadowError(RuntimeError):
    """A failure the user can act on; ``str(error)`` is the message to show."""


@dataclass(frozen=True)
class Cutout:
    """The canvas-sized alpha the shadow is cast from."""

    width: int
    height: int
    dtype: str
    data: bytes
    source: str  # for messages, e.g. "the selection" or 'layer "Pawn"'


@dataclass(frozen=True)
class ShadowLayerData:
    """A shadow layer from the worker: place on the canvas and straight-alpha RGBA pixels."""

    x: int
    y: int
    width: int
    height: int
    dtype: str
    data: bytes
    no_shadow: str = ""  # why the layer is empty (the worker's reason), "" when it is not


class Host(Protocol):
    """What the run logic needs from the image editor."""

    def pixel_plan(self) -> PixelPlan: ...

    def source_name(self) -> str: ...

    def hidden_reason(self) -> str | None: ...

    def read_cutout(self, plan: PixelPlan) -> Cutout: ...

    def undo_group_start(self) -> None: ...

    def undo_group_end(self) -> None: ...

    def add_shadow_layer(self, name: str, shadow: ShadowLayerData, plan: PixelPlan) -> Any: ...


class Engine(Protocol):
    """The host kit's client (:class:`ssn_engine.host_kit.client.EngineClient`), or a stand-in."""

    @property
    def running(self) -> bool: ...

    def request(self, cmd: str, buffers: dict | None = None, *, timeout: float | None = None, **params: Any) -> Any: ...


def shadow_layer_name(source_name: str) -> str:
    return f"{LAYER_PREFIX}{source_name}"


def target_note(layer: str, replacing: str | None, selection: tuple[int, int] | None) -> str:
    """What the dialog says the filter casts, as :meth:`Host.read_cutout` does: the selection where there is one
    (``selection``: the width and height of its bounds; the layer ``layer`` only takes the shadow), else the
    layer's alpha; and the shadow layer it replaces (``replacing``), if any."""
    if selection is None:
        note = f'Casting the shadow of the layer "{layer}"'
    else:
        note = f'Casting the shadow of the selection ({selection[0]} x {selection[1]} pixels) in "{layer}"'
    if replacing is not None:
        note += f', replacing "{replacing}"'
    note += "."
    if selection is not None:
        note += " To cast the layer's own outline, choose Select > None first."
    return note


def engine_call(engine: Engine, cmd: str, buffers: dict | None = None, **params: Any) -> tuple[dict, dict]:
    """``engine.request``, its failures as :class:`ShadowError`; the user's Cancel passes as it is
    (:class:`~ssn_engine.host_kit.client.Cancelled`: no error to show)."""
    try:
        return engine.request(cmd, buffers, **params)
    except engine_client.Cancelled:
        raise
    except engine_client.EngineError as exc:
        raise ShadowError(str(exc)) from None
    except (OSError, protocol.ProtocolError) as exc:
        raise ShadowError(f"Lost contact with the shadow engine: {exc}") from None


def send_cutout(
    engine: Engine, cutout: Cutout, camera: dict[str, float] | None = None, geometry: dict[str, Any] | None = None
) -> dict[str, Any]:
    """Send the alpha (and the image's camera, if set, and the artist's ``geometry``, ``lift`` and ``thickness``,
    if given) to the worker, which predicts AO now; return its reply: ``cutout`` (the id), ``bbox`` (x0, y0, x1,
    y1 on the canvas) and, without a camera, ``camera_read`` where the model read one."""
    if cutout.width <= 0 or cutout.height <= 0:
        raise ShadowError("The image is empty.")
    if is_blank(cutout.data):
        raise ShadowError(
            f"Nothing to cast a shadow from: {cutout.source} is fully transparent. "
            "Select the object or paint it on a layer with a transparent background."
        )
    alpha = protocol.Buffer(cutout.dtype, (cutout.height, cutout.width), cutout.data)
    params: dict[str, Any] = {"camera": camera} if camera else {}
    reply, _ = engine_call(engine, "set_cutout", {"alpha": alpha}, **params, **(geometry or {}))
    return reply


def upload_cutout(
    engine: Engine, cutout: Cutout, camera: dict[str, float] | None = None, geometry: dict[str, Any] | None = None
) -> tuple[str, dict[str, float] | None]:
    """:func:`send_cutout`; return the cutout id and, without a camera, the one the model read from the outline
    ({"horizon": row, "fov": degrees} in the cutout's pixels; None where it reads none)."""
    reply = send_cutout(engine, cutout, camera, geometry)
    return str(reply["cutout"]), reply.get("camera_read")


def set_camera(engine: Engine, cutout_id: str, camera: dict[str, float] | None) -> dict[str, float] | None:
    """Give an uploaded cutout another camera (None: the one the model reads) without sending its alpha again: the
    worker predicts its AO again. Returns the camera the model read, as :func:`upload_cutout` does."""
    reply, _ = engine_call(engine, "set_camera", cutout=cutout_id, camera=camera)
    return reply.get("camera_read")


def set_geometry(engine: Engine, cutout_id: str, lift: float, thickness: float | None) -> dict[str, Any]:
    """Give an uploaded cutout the artist's geometry (``lift`` canvas rows, ``thickness`` or None: read) without
    sending its alpha again; the worker's reply, with ``thickness_read`` (what the outline reads as). A refusal (a
    lift whose ground lies at or above the horizon) is a :class:`ShadowError` with the engine's message; the
    cutout keeps its geometry."""
    reply, _ = engine_call(engine, "set_geometry", cutout=cutout_id, lift=lift, thickness=thickness)
    return reply


def checked_lift(lift: float, canvas_height: int) -> float:
    """``lift`` where a canvas ``canvas_height`` rows tall takes it (:func:`geometry_rules.check_lift`), else a
    :class:`ShadowError` that says the range (a script's argument; the dialog clamps instead)."""
    try:
        return geometry_rules.check_lift(lift, canvas_height)
    except ValueError as exc:
        raise ShadowError(f"{exc}. Nothing was changed.") from None


def render_shadow(
    engine: Engine, cutout_id: str, settings: ShadowSettings, dtype: str, canvas: tuple[int, int]
) -> ShadowLayerData:
    """Apply the AO edits and render the shadow layer in ``dtype`` for a ``canvas`` (width, height)."""
    edits = settings.ao_edits()
    if edits:
        engine_call(engine, "edit_ao", cutout=cutout_id, edits=edits)
    reply, buffers = engine_call(engine, "render", cutout=cutout_id, **settings.render_params(dtype, canvas))
    x, y, w, h = (int(reply[k]) for k in ("x", "y", "width", "height"))
    if w == 0 or h == 0:
        return ShadowLayerData(x, y, 0, 0, dtype, b"", str(reply.get("no_shadow") or ""))
    layer = buffers.get("layer")
    if layer is None or layer.dtype != dtype or tuple(layer.shape) != (h, w, 4):
        got = "nothing" if layer is None else f"{layer.dtype} {tuple(layer.shape)}"
        raise ShadowError(f"The shadow engine sent a malformed layer: expected {dtype} {(h, w, 4)}, got {got}.")
    data = bytes(memoryview(layer.data).cast("B"))
    if len(data) != w * h * 4 * BYTES_PER_SAMPLE[dtype]:
        raise ShadowError("The shadow engine sent a truncated layer.")
    return ShadowLayerData(x, y, w, h, dtype, data)


def release(engine: Engine, cutout_id: str) -> None:
    """Free the worker's cutout; best effort (the worker may be gone). A stopped worker (a Cancel, a crash) took
    its cutouts with it: no fresh one is started to free nothing."""
    if not engine.running:
        return
    try:
        engine.request("release", cutout=cutout_id)
    except Exception:  # noqa: BLE001 - cleanup must never hide the real outcome
        pass


def compute_shadow(host: Host, engine: Engine, settings: ShadowSettings) -> tuple[ShadowLayerData, PixelPlan]:
    """Read the cutout and render its shadow; touches nothing in the image."""
    if settings.opacity <= 0:
        raise ShadowError("The opacity is 0, so the shadow layer would show nothing. Raise the opacity.")
    hidden = host.hidden_reason()
    if hidden:
        raise ShadowError(hidden)
    plan = host.pixel_plan()
    cutout = host.read_cutout(plan)
    checked_lift(settings.lift, cutout.height)
    cutout_id, _ = upload_cutout(engine, cutout, settings.camera(), settings.cutout_geometry())
    try:
        shadow = render_shadow(engine, cutout_id, settings, plan.layer_dtype, (cutout.width, cutout.height))
    finally:
        release(engine, cutout_id)
    if shadow.width == 0:
        raise ShadowError(shadow_notes.no_shadow_note(shadow.no_shadow))
    return shadow, plan


def make_shadow(host: Host, engine: Engine, settings: ShadowSettings | dict[str, Any]) -> Any:
    """The whole filter: compute the shadow, then add it below the drawable in one undo group.

    ``settings`` may be a :class:`ShadowSettings` or a dict of argument values
    keyed like the procedure's arguments ("light-map", "shadow-color", ...).
    Returns whatever ``host.add_shadow_layer`` returns (the new layer).
    """
    if isinstance(settings, dict):
        settings = settings_from_arguments(settings)
    shadow, plan = compute_shadow(host, engine, settings)
    host.undo_group_start()
    try:
        return host.add_shadow_layer(shadow_layer_name(host.source_name()), shadow, plan)
    finally:
        host.undo_group_end()


def settings_from_arguments(values: dict[str, Any]) -> ShadowSettings:
    """Build settings from procedure argument values (missing ones take their defaults).

    Errors become :class:`ShadowError`.
    """

    def get(name: str) -> Any:
        return values.get(name, ARG_BY_NAME[name].default)

    try:
        return ShadowSettings(
            light_map=get("light-map"),
            color=tuple(get("shadow-color"))[:3],
            opacity=get("opacity"),
            ao_strength=get("ao-strength"),
            horizon=get("horizon") if get("use-horizon") else None,
            fov=get("fov"),
            keep_whole=bool(get("keep-whole-shadow")),
            lift=get("lift"),
            thickness=thickness_setting(get("thickness")),
        )
    except SettingsError as exc:
        raise ShadowError(str(exc)) from None


def thickness_setting(argument: Any) -> Any:
    """The thickness setting of a thickness argument: None (read from the outline) below 0, else the value (a bad
    one is refused by :class:`ShadowSettings`, naming the argument)."""
    if isinstance(argument, (int, float)) and not isinstance(argument, bool) and argument < 0:
        return None
    return argument
