"""Runs in the plug-in's Set up dialog (SSN_SHADOW_SETUP_TEST): press Set up, and print each text the dialog shows
until it closes itself (the engine set up). With a file ``shot.txt`` beside this script (naming a PNG path), it
also saves a picture of the dialog while it installs (docs/img/gimp-setup.png)."""

import os
import sys

from gi.repository import Gdk, GLib

parts = globals()["parts"]
shown = []
shot_list = os.path.join(os.path.dirname(globals()["__file__"]), "shot.txt")
shot = open(shot_list).read().strip() if os.path.exists(shot_list) else ""


def watch() -> bool:
    global shot
    text = parts.message.get_text()
    if text not in shown:
        shown.append(text)
        print(f"ssn-shadow set-up dialog: {parts.progress.get_fraction():.2f} {text}", file=sys.stderr, flush=True)
    if shot and parts.progress.get_fraction() >= 0.3:
        window = parts.dialog.get_window()
        Gdk.pixbuf_get_from_window(window, 0, 0, window.get_width(), window.get_height()).savev(shot, "png", [], [])
        shot = ""
    return True


print(f"ssn-shadow set-up dialog: offered {parts.action.get_label()!r}", file=sys.stderr, flush=True)
parts.dialog.response(1)  # Set up
GLib.timeout_add(100, watch)
