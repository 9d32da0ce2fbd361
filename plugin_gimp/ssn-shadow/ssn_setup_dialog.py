"""The GIMP plug-in's Set up dialog: shown when a packaged plug-in has no engine (or an older one) before the filter's
dialog opens. It runs the host kit's :class:`engine_setup.SetupJob` off GIMP's UI thread, with a progress bar, a
Cancel that stops it and an Open log; thin: what to say and how to set up are the kit's."""

from __future__ import annotations

import os
from types import SimpleNamespace

import gi

gi.require_version("Gimp", "3.0")
gi.require_version("GimpUi", "3.0")
gi.require_version("Gtk", "3.0")
from gi.repository import Gio, GimpUi, GLib, Gtk  # noqa: E402
from ssn_engine_link import engine_config, engine_setup  # noqa: E402

SETUP, LOG = 1, 2  # the dialog's own responses
POLL_MS = 100
TEST_SCRIPT_ENV = "SSN_SHADOW_SETUP_TEST"  # the integration test's script (it presses the buttons itself)


def run_setup_dialog(needed: engine_config.EngineSetupNeeded, title: str) -> bool:
    """Offer Set up (or Update); True once the engine is set up, False if the dialog was closed without it."""
    GimpUi.init("ssn-shadow")
    dialog = Gtk.Dialog(title=f"{title}: set up the engine")
    dialog.add_button("_Close", Gtk.ResponseType.CLOSE)
    dialog.add_button("Open _log", LOG)
    action = dialog.add_button("_Update" if needed.state.status == "outdated" else "_Set up", SETUP)
    message = Gtk.Label(label=str(needed), xalign=0.0)
    message.set_line_wrap(True)
    message.set_max_width_chars(56)
    progress = Gtk.ProgressBar(show_text=True)
    box = dialog.get_content_area()
    box.set_spacing(12)
    box.set_border_width(12)
    box.pack_start(message, False, False, 0)
    box.pack_start(progress, False, False, 0)
    box.show_all()
    progress.set_visible(False)
    log_path = engine_setup.data_dir() / "setup.log"
    state = SimpleNamespace(job=None, ready=False, loop=GLib.MainLoop())

    def poll() -> bool:
        for event in state.job.events():
            progress.set_fraction(event.fraction)
            message.set_text(event.text)
            if event.done:
                state.ready = not event.error
                if state.ready:  # on to the filter's dialog
                    dialog.response(Gtk.ResponseType.CLOSE)
                else:
                    action.set_sensitive(True)
                    action.set_label("_Resume" if event.cancelled else "_Try again")
                return False
        return True

    def on_response(_dialog, response: int) -> None:
        if response == SETUP:
            setup = engine_setup.EngineSetup(needed.bundle, engine_setup.data_dir())
            state.job = engine_setup.SetupJob(setup).start()
            action.set_sensitive(False)
            progress.set_visible(True)
            progress.set_fraction(0.0)
            GLib.timeout_add(POLL_MS, poll)
        elif response == LOG:
            if log_path.exists():
                Gio.AppInfo.launch_default_for_uri(log_path.as_uri(), None)
        elif state.job is not None and state.job.running:  # Close while it runs: cancel, then close
            state.job.cancel()
            message.set_text("Cancelling...")
            state.job.wait(30)
            state.loop.quit()
        else:
            state.loop.quit()

    dialog.connect("response", on_response)
    dialog.connect("delete-event", lambda *_: on_response(dialog, Gtk.ResponseType.CLOSE) or True)
    script = os.environ.get(TEST_SCRIPT_ENV, "")
    if script:
        parts = SimpleNamespace(dialog=dialog, message=message, progress=progress, action=action, state=state)
        GLib.timeout_add(300, _run_test_script, script, parts)
    dialog.show()
    try:
        state.loop.run()
    finally:
        dialog.destroy()
    return state.ready


def _run_test_script(path: str, parts: SimpleNamespace) -> bool:
    """For the integration test: run its script with the dialog's parts; it presses the buttons itself."""
    with open(path, encoding="utf-8") as script:
        exec(compile(script.read(), path, "exec"), {"__file__": path, "parts": parts})  # noqa: S102 - a test's own
    return False
