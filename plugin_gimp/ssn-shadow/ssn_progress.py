"""What the filter shows while the engine works: GIMP's progress bar, and a way out.

:class:`EngineWait` is the engine client's ``on_wait`` hook
(:func:`ssn_engine.host_kit.client.wait_for`), asked about every 50 ms while
a reply is awaited. It shows GIMP's progress in the image window (pulsing:
the engine says nothing about how far it is); GIMP's own Cancel there stops
the plug-in, and its worker with it, and leaves the image as it was (the
layer is only written after the engine's last reply). In the dialog it also
handles the dialog's events meanwhile (a frozen worker leaves the dialog
working) and ends the wait when the dialog's :meth:`cancel` is pressed.
"""

from __future__ import annotations

import time
from collections.abc import Callable

import gi

gi.require_version("Gimp", "3.0")
from gi.repository import Gimp  # noqa: E402

MESSAGE = "Soft Shadow: waiting for the shadow engine"
PULSE_EVERY = 0.2  # seconds between two pulses of the progress bar


class EngineWait:
    """The client's ``on_wait`` hook: progress, the dialog's events, and the dialog's Cancel."""

    def __init__(self) -> None:
        self.handle_events: Callable[[], None] | None = None  # the dialog's event pump, while it is open
        self.cancelled = False  # set by :meth:`cancel`, cleared by :meth:`reset`
        self._shown = False
        self._pulsed = 0.0

    def __call__(self) -> bool:
        now = time.monotonic()
        if now - self._pulsed >= PULSE_EVERY:
            if not self._shown:
                Gimp.progress_init(MESSAGE)
                self._shown = True
            Gimp.progress_pulse()
            self._pulsed = now
        if self.handle_events is not None:
            self.handle_events()
        return self.cancelled

    def cancel(self) -> None:
        """Stop the wait under way (the client stops the worker and raises Cancelled)."""
        self.cancelled = True

    def reset(self) -> None:
        """Ready for the next wait: not cancelled, and the progress bar, if shown, gone (the dialog's previews)."""
        self.cancelled = False
        if self._shown:
            Gimp.progress_end()
            self._shown = False
