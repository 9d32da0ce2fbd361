#!/usr/bin/env python3
"""GIMP 3 plug-in "Soft Shadow (SSN)": a soft shadow layer cast by the selection or the layer's alpha.

Filters > Light and Shadow > Soft Shadow (SSN)... The plug-in is thin: the
shadow is predicted by the ssn-shadow engine worker (``ssn-shadow serve``),
reached through ``engine.json`` beside this file. Procedure: ``plug-in-ssn-shadow``.
"""

from __future__ import annotations

import os
import sys
import traceback

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))

import gi  # noqa: E402

gi.require_version("Gimp", "3.0")
gi.require_version("Gegl", "0.4")
gi.require_version("Babl", "0.1")
from gi.repository import Babl, Gegl, Gimp, GLib, GObject  # noqa: E402

from ssn_core import ShadowError, make_shadow  # noqa: E402
from ssn_gimp_host import GimpHost, config_values  # noqa: E402
from ssn_engine_link import client as engine_client  # noqa: E402
from ssn_engine_link import connect, engine_config  # noqa: E402
from ssn_progress import EngineWait  # noqa: E402
from ssn_settings import (  # noqa: E402
    ARGUMENTS,
    IMAGE_TYPES,
    MENU_LABEL,
    MENU_PATH,
    PROCEDURE_BLURB,
    PROCEDURE_HELP,
    PROCEDURE_NAME,
)

RW = GObject.ParamFlags.READWRITE


def add_arguments(procedure: Gimp.Procedure) -> None:
    """Register every setting of ssn_settings.ARGUMENTS as a procedure argument."""
    for spec in ARGUMENTS:
        if spec.kind == "string":
            procedure.add_string_argument(spec.name, spec.label, spec.blurb, spec.default, RW)
        elif spec.kind == "double":
            procedure.add_double_argument(spec.name, spec.label, spec.blurb, spec.lo, spec.hi, spec.default, RW)
        elif spec.kind == "boolean":
            procedure.add_boolean_argument(spec.name, spec.label, spec.blurb, spec.default, RW)
        elif spec.kind == "color":
            default = Gegl.Color.new("black")
            default.set_rgba_with_space(*spec.default, 1.0, Babl.space("sRGB"))
            procedure.add_color_argument(spec.name, spec.label, spec.blurb, False, default, RW)
        else:  # pragma: no cover - a programming error in ARGUMENTS
            raise ValueError(f"unknown argument kind {spec.kind!r}")
    procedure.add_layer_return_value("shadow-layer", "Shadow layer", "The new shadow layer", True, RW)


def failure(procedure: Gimp.Procedure, message: str) -> Gimp.ValueArray:
    return procedure.new_return_values(Gimp.PDBStatusType.EXECUTION_ERROR, GLib.Error(message))


class SoftShadow(Gimp.PlugIn):
    """The plug-in: one image procedure."""

    def do_query_procedures(self):
        return [PROCEDURE_NAME]

    def do_set_i18n(self, name):
        return False

    def do_create_procedure(self, name):
        Gegl.init(None)
        procedure = Gimp.ImageProcedure.new(self, name, Gimp.PDBProcType.PLUGIN, self.run, None)
        procedure.set_image_types(IMAGE_TYPES)
        procedure.set_sensitivity_mask(Gimp.ProcedureSensitivityMask.DRAWABLE)
        procedure.set_menu_label(MENU_LABEL)
        procedure.add_menu_path(MENU_PATH)
        procedure.set_documentation(PROCEDURE_BLURB, PROCEDURE_HELP, name)
        procedure.set_attribution("ssn-shadow contributors", "ssn-shadow contributors", "2025")
        add_arguments(procedure)
        return procedure

    def run(self, procedure, run_mode, image, drawables, config, data):
        try:
            return self._run(procedure, run_mode, image, drawables, config)
        except engine_client.Cancelled:
            return procedure.new_return_values(Gimp.PDBStatusType.CANCEL, GLib.Error())
        except (ShadowError, engine_client.EngineError, engine_config.EngineConfigError) as exc:
            return failure(procedure, str(exc))  # EngineError: from connect (no worker could be had), as written
        except Exception:  # noqa: BLE001 - never crash GIMP; report the bug instead
            return failure(procedure, "Soft Shadow failed unexpectedly (a bug):\n" + traceback.format_exc(limit=6))

    def _run(self, procedure, run_mode, image, drawables, config):
        if len(drawables) != 1:
            raise ShadowError("Soft Shadow works on one layer: select exactly one layer.")
        host = GimpHost(image, drawables[0])
        if run_mode != Gimp.RunMode.NONINTERACTIVE:  # GIMP's last values are any image's: the camera and the
            for name, value in {**host.image_camera(), **host.image_geometry()}.items():  # geometry are this one's
                config.set_property(name, value)
        wait = EngineWait()  # GIMP's progress while the engine works; its Cancel stops this plug-in
        engine = connect_or_set_up(run_mode, wait)
        try:
            if run_mode == Gimp.RunMode.INTERACTIVE:
                import ssn_dialog

                if not ssn_dialog.run_dialog(procedure, config, host, engine):
                    return procedure.new_return_values(Gimp.PDBStatusType.CANCEL, GLib.Error())
                if not engine.running:  # OK pressed while a preview waited: its worker was stopped
                    engine.close()
                    engine = connect(on_wait=wait)
            layer = make_shadow(host, engine, config_values(config))
        finally:
            engine.close()
        if run_mode == Gimp.RunMode.INTERACTIVE:
            host.remember_camera(config_values(config))
            host.remember_geometry(config_values(config))
        Gimp.displays_flush()
        return Gimp.ValueArray.new_from_values(
            [GObject.Value(Gimp.PDBStatusType, Gimp.PDBStatusType.SUCCESS), GObject.Value(Gimp.Layer, layer)]
        )


def connect_or_set_up(run_mode: Gimp.RunMode, wait: EngineWait) -> engine_client.EngineClient:
    """The engine; a packaged plug-in without one offers Set up first (interactive runs; others say how)."""
    try:
        return connect(on_wait=wait)
    except engine_config.EngineSetupNeeded as needed:
        if run_mode != Gimp.RunMode.INTERACTIVE:
            menu = " > ".join([*MENU_PATH.split("/")[1:], MENU_LABEL.replace("_", "")])
            raise engine_config.EngineConfigError(f"{needed} Open {menu} once and press Set up.") from None
        import ssn_setup_dialog

        if not ssn_setup_dialog.run_setup_dialog(needed, MENU_LABEL.replace("_", "").rstrip(".")):
            raise engine_client.Cancelled("set-up") from None
        return connect(on_wait=wait)


if __name__ == "__main__":
    Gimp.main(SoftShadow.__gtype__, sys.argv)
