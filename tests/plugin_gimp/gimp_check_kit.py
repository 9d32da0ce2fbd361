"""Runs INSIDE GIMP 3: what the *_check.py scripts share, imported by them (the tests copy it beside them and put
that folder on sys.path; see test_gimp_integration.py's ``KIT_SCRIPT``).

Calling the filter, reading the image back, showing it in a window, and (the cancel checks) a helper process that
presses or clicks once the frozen worker (tests/hung_worker.py) has frozen.
"""

import subprocess
import sys
import textwrap

import gi

gi.require_version("Gimp", "3.0")
gi.require_version("Gegl", "0.4")
from gi.repository import Gegl, Gimp  # noqa: E402

HANG = 1.5  # seconds the frozen worker hangs before the helper process presses or clicks
PRESSER_WAIT = """
import os, subprocess, sys, time
frozen = {frozen!r}
deadline = time.time() + 120
while not os.path.exists(frozen) and time.time() < deadline:
    time.sleep(0.05)
time.sleep({hang})
def xdotool(*args):
    return subprocess.run(["xdotool", *args], capture_output=True, text=True, timeout=20).stdout.split()
"""


def call_filter(image, layer, mode, properties=None):
    """Run plug-in-ssn-shadow on ``layer`` of ``image`` in ``mode`` (a Gimp.RunMode), its config's
    ``properties`` (by name) set too; its return values (a Gimp.ValueArray)."""
    proc = Gimp.get_pdb().lookup_procedure("plug-in-ssn-shadow")
    config = proc.create_config()
    config.set_property("run-mode", mode)
    config.set_property("image", image)
    config.set_core_object_array("drawables", [layer])
    for name, value in (properties or {}).items():
        config.set_property(name, value)
    return proc.run(config)


def layer_names(image):
    """The names of ``image``'s layers, top first."""
    return [lay.get_name() for lay in image.get_layers()]


def pixels(drawable):
    """``drawable``'s pixels as 8-bit RGBA bytes."""
    rect = Gegl.Rectangle.new(0, 0, drawable.get_width(), drawable.get_height())
    return bytes(drawable.get_buffer().get(rect, 1.0, "R'G'B'A u8", Gegl.AbyssPolicy.NONE))


def show(image, layer):
    """Show ``image`` (its ``layer`` written out, nothing to save) in an image window of the GUI."""
    layer.get_buffer().flush()
    image.clean_all()
    Gimp.Display.new(image)
    Gimp.displays_flush()


def process_alive(pid):
    """Whether process ``pid`` runs (a zombie does not)."""
    try:
        with open(f"/proc/{pid}/stat") as f:
            return f.read().rsplit(")", 1)[1].split()[0] != "Z"
    except FileNotFoundError:
        return False


def start_presser(pid_file, action):
    """A helper process that waits for the frozen worker to write ``pid_file`` + ".frozen", lets it hang ``HANG``
    seconds, then runs ``action``: Python that may call ``xdotool(*args)`` (the words of its output) and read
    ``frozen`` (that file's path), and prints what it reports."""
    script = PRESSER_WAIT.format(frozen=pid_file + ".frozen", hang=HANG) + textwrap.dedent(action)
    return subprocess.Popen([sys.executable, "-c", script], stdout=subprocess.PIPE, text=True)


def presser_said(presser):
    """The words the helper process ``presser`` printed (none if it is not done within 30 s: then it is killed)."""
    try:
        return presser.communicate(timeout=30)[0].split()
    except subprocess.TimeoutExpired:
        presser.kill()
        return []
