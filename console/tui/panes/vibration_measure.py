"""The Vibration screen's measurement of the map on the twin (``m``, the typed
``measure``): with a kept map it asks first (``m`` again, or Enter again on the line
keeping the typed command); it says its progress and the time left, and
``x`` or an e-stop stops it (said as such). With an accelerometer input ``m`` runs the
roving measurement instead (``console.tui.roving_view``)."""

from __future__ import annotations

import threading
import time
from typing import Any

from console.core.errors import UserError
from console.core.words import AT_CONSOLE, worded
from console.session.events import ESTOP_FIX, ESTOP_REFUSAL
from console.session.vibration import Cancelled
from console.tui.lapse import ask, lapse
from console.tui.long_work import stop_check
from console.tui.panes.vibration_words import (
    MAP_FREE,
    MEASURE_AGAIN_S,
    MEASURE_ESTOPPED,
    measure_again,
    with_time_left,
)
from console.tui.question_hold import answered
from console.tui.roving_view import RovingView, add_accelerometer_text
from console.tui.util import from_thread
from console.tui.workers import work


class VibrationMeasureMixin:
    """``m`` on the Vibration screen (``VibrationPane``: its status line ``status``,
    ``_error``, stop flags ``_new_stop``, ``service`` and ``_show_map``)."""

    app: Any
    roving: RovingView
    service: Any
    summary: str
    status_text: str
    _measuring: threading.Event | None
    _measure_asked = -1e9  # when m (or the typed measure) last asked before replacing
    _command_asks = False  # the typed command asked: its line keeps it for Enter again
    #: the one-line accelerometer hint ``m`` shows without an accelerometer input ("": none);
    #: it goes with the next key or when the measurement ends, whichever comes first
    _accel_hint = ""

    def action_measure(self, command: str | None = None) -> None:
        """``m``: measure the map, refused in the console's words during an e-stop, and
        while a run plays on the map (``refuse_replacing``). Pressed while it asks:
        the question is answered (its line is free for what ``m`` does now)."""
        answered(self)
        if self.refuse_replacing("measure"):
            return
        if (self.roving.running or self.roving.wanted()) and not self._estop_active():
            self.roving.measure(command)
            return
        if self._estop_active():
            self._error(f"measure {ESTOP_REFUSAL}, {ESTOP_FIX}")
            return
        now = time.monotonic()
        kept = self.service.cached_map_path().is_file()
        if kept and now - self._measure_asked > MEASURE_AGAIN_S:  # it would be replaced
            again = "m" if command is None else "Enter"  # the typed one waits on its line
            self._command_asks = command is not None
            takes = self.service.measure_takes()
            self._measure_asked, asked = now, measure_again(takes, again)
            then, shown = self.summary, lambda: self.status_text  # the map's line after
            # the question holds the line until it lapses (or m answers it)
            ask(self, shown, asked, self.status, MEASURE_AGAIN_S, then=then)
            return
        self._measure_asked = -1e9
        self.status("measuring ...", 0.0)
        self._accel_hint = add_accelerometer_text(self.app.session.table_profile)
        self.roving.say(self._accel_hint)
        self._measuring = stop = self._new_stop("vib-long")  # an e-stop sets it too
        self._measure(stop, command)

    def refuse_replacing(self, what: str) -> bool:
        """Whether ``what`` (``measure``, ``load``, ``import``) would replace the map a
        run plays on: then the line says so, as a play refused while a run holds the
        outputs, until that run ends (``console.session.vibration``: ``in_use``)."""
        why = self.service.refusal(what)
        if not why:
            return False
        self._measure_asked = -1e9  # a question asked before is void
        self._error(why)
        service = self.service
        lapse(
            self,
            lambda: self.status_text,
            why,
            self.status,
            while_true=lambda: service.used_by is not None,
            then=MAP_FREE,
        )
        return True

    @work(thread=True, exclusive=True, group="vib-long", what="the measurement")
    def _measure(self, stop: threading.Event, command: str | None = None) -> None:
        """The measurement; x or an e-stop stops it (the e-stop polled here as well: it
        stops at once even before its message reaches the screen)."""
        stopped = stop_check(stop)

        def cancelled() -> bool:
            return stopped() or self._estop_active()

        def shown(frac: float, msg: str) -> None:
            if not cancelled():
                from_thread(self.app, self._measure_progress, stop, f"measuring: {msg}", frac)

        progress = with_time_left(shown, self.service.measure_s())  # a time left at once

        try:
            self._show_map(self.service.measure(progress, cancelled))
            from_thread(self.app, self._command_done, command, True)
        except Cancelled:
            from_thread(self.app, self._measure_cancelled, stop, command)
        except UserError as exc:
            from_thread(self.app, self._error, worded(exc, AT_CONSOLE))
            from_thread(self.app, self._command_done, command, False)
        finally:
            from_thread(self.app, self._measure_ended, stop)

    def _measure_progress(self, stop: threading.Event, text: str, frac: float) -> None:
        if not stop.is_set() and not self._estop_active():
            self.status(text, frac)

    def _measure_cancelled(self, stop: threading.Event, command: str | None) -> None:
        """A measurement stopped: by the e-stop (said as such) or by x."""
        if self._estop_active():
            self._measure_estopped()
        elif stop is self._measuring:
            self.status("measurement cancelled; the map is unchanged")
        self._command_done(command, False)

    def _measure_ended(self, stop: threading.Event) -> None:
        if stop is self._measuring:
            self._measuring = None
            self.drop_accelerometer_hint()  # measured, cancelled or failed: said

    def drop_accelerometer_hint(self) -> None:
        """The accelerometer hint goes (the grid moves back up); ``?`` says it whole."""
        if self._accel_hint:
            self.roving.unsay(self._accel_hint)
            self._accel_hint = ""

    def on_key(self, event: Any) -> None:
        """The next key after ``m`` (on its way to what it does) takes the hint away."""
        self.drop_accelerometer_hint()

    def _measure_estopped(self) -> None:
        """The line says the e-stop stopped the measurement (once)."""
        if self.status_text != MEASURE_ESTOPPED:
            self._error(MEASURE_ESTOPPED)
