"""Runs in the plug-in's Set up dialog (SSN_SHADOW_SETUP_TEST): press Set up, and print each text the dialog shows
until it closes itself (the engine set up)."""

import sys

from gi.repository import GLib

parts = globals()["parts"]
shown = []


def watch() -> bool:
    text = parts.message.get_text()
    if text not in shown:
        shown.append(text)
        print(f"ssn-shadow set-up dialog: {parts.progress.get_fraction():.2f} {text}", file=sys.stderr, flush=True)
    return True


print(f"ssn-shadow set-up dialog: offered {parts.action.get_label()!r}", file=sys.stderr, flush=True)
parts.dialog.response(1)  # Set up
GLib.timeout_add(100, watch)
