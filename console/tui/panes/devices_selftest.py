"""The Devices screen's self-test (key s): asked first, run in a worker
(``console.tui.selftest_action``), its progress on the status line while it runs, its
outcome on the status line and in the device table's self-test row (kept across
restarts: ``console.runtime.selftest_last``)."""

from __future__ import annotations

import time
from typing import Any

from console.core.types import DeviceStatus
from console.runtime.selftest_last import forget_last, note_last, read_last
from console.session.events import ESTOP_FIX, estop_refusal
from console.tui.ask_again import AskAgain
from console.tui.selftest_action import (
    run_selftest,
    selftest_about,
    selftest_progress,
    selftest_row,
)
from console.tui.selftest_stopped import kept_stopped, stopped_when
from console.tui.util import from_thread
from console.tui.workers import work


class DevicesSelftestMixin:
    """``s`` on ``DevicesPane`` (its status line ``_show_result``/``_say``, ``_profile``,
    the device table ``_show`` and ``doctor_rows``)."""

    app: Any
    ask: AskAgain
    result: str
    doctor_rows: list[DeviceStatus]
    #: the self-test's row: its last run here (None: not run), its seconds then
    selftest_done: tuple[bool, str, float] | None
    #: the last run here stopped before its end: when and by what ("" : it was not)
    selftest_stopped: str
    #: `haptable doctor`'s quick part's line when it skips now ("": it would run)
    quick_skips: str

    def _selftest_status(self) -> DeviceStatus:
        """The self-test's row of the device table now (``selftest_row``): its run here,
        else what was kept (`haptable doctor`'s quick part, a run stopped here or in an
        earlier session of the console)."""
        last = read_last(self._profile().name)
        out = self.app.session.outputs
        estopped = out is not None and out.estopped
        kept = last.get("stopped")
        stopped = self.selftest_stopped or (kept_stopped(kept) if kept else "")
        return selftest_row(self.selftest_done, last, stopped, estopped, self.quick_skips)

    def action_selftest(self) -> None:
        """``s``: asks first, saying its paths and time (it plays chirps on every relay
        path), ``s`` again within 3 s runs it; during an e-stop it is refused at once
        (nothing to ask)."""
        out = self.app.session.outputs
        if out is not None and out.estopped:  # nothing to ask: the console's key first
            self._show_result(f"self-test {estop_refusal(out.estop_reason or '')}", error=True)
            return
        if self.ask.confirmed("selftest"):
            self._selftest()
            return
        last_s = self.selftest_done[2] if self.selftest_done else 0.0
        about = selftest_about(self._profile(), self.app.ctx.pm, last_s)[0]
        does = f"runs the self-test ({about}): a chirp on every relay path"
        self.ask.ask(self, "s", does, lambda: self.result, self._show_result)

    @work(thread=True, exclusive=True, group="test-output")
    def _selftest(self) -> None:
        """Every relay path chirped and compared (``console.tui.selftest_action``): the
        line says how long it takes before it starts, then how far it is."""
        prof, pm = self._profile(), self.app.ctx.pm
        last_s = self.selftest_done[2] if self.selftest_done else 0.0
        about, total_s, est = selftest_about(prof, pm, last_s)
        out = self.app.session.outputs
        self._estopped_at_start = out is not None and out.estopped
        self._say(f"self-test ({about}): starting ...")
        t0 = time.monotonic()
        from_thread(self.app, self._selftest_ticks, t0, total_s, est)
        ok, line = run_selftest(prof, pm)
        if ok is not None:  # it ran: kept for the row after a restart
            note_last(prof.name, "full", "ok" if ok else "error", line, "the console's s")
        took_s = 0.0 if est and est[2] else time.monotonic() - t0  # a map run: no guide
        from_thread(self.app, self._selftest_ended, ok, line, took_s)

    def _selftest_ticks(self, t0: float, total_s: float, est) -> None:
        """While the self-test runs: the line says what it does and the time left
        (``selftest_progress``)."""

        self._selftest_clock = (t0, total_s, est)
        self._selftest_timer = self.set_interval(0.5, self._selftest_tick)

    def _selftest_tick(self) -> None:
        """The self-test's progress on the line (a key's answer holds it ``NOTE_S``
        against the ticks: ``console.tui.question_hold``)."""
        t0, total_s, est = self._selftest_clock
        self._show_result(selftest_progress(time.monotonic() - t0, total_s, est), tick=True)

    def _selftest_ended(self, ok: bool | None, line: str, took_s: float) -> None:
        prof_name = self._profile().name
        if self._selftest_timer is not None:
            self._selftest_timer.stop()
            self._selftest_timer = None
        if ok is None:  # refused (the row keeps the last result) or stopped under way
            out = self.app.session.outputs
            at, what = time.strftime("%H:%M:%S"), ""
            if out is not None and out.estopped and not self._estopped_at_start:
                # under way when the e-stop came: stopped, not refused; the reset's line
                # replaces this one (``_says_estop``)
                line = f"self-test stopped by the e-stop before its end; {ESTOP_FIX}, then s"
                line += " runs it again"
                what = "by the e-stop"
            elif line.startswith("self-test stopped"):
                what = line.split("(", 1)[-1].rstrip(")")
            if what:  # kept for the row after a restart (its time kept beside it)
                self.selftest_stopped = stopped_when(what, at)
                note_last(prof_name, "stopped", "stopped", what, "the console's s")
            if self.selftest_stopped and self.doctor_rows:  # the row says it too: its
                self._show(self.doctor_rows[:-1])  # last outcome is not this run's
            self._show_result(line, error=True)
            return
        self.selftest_done, self.selftest_stopped = (ok, line, took_s), ""
        forget_last(prof_name, "stopped")  # a whole run ended: the stopped one is past
        self._show_result(line, error=not ok)
        if self.doctor_rows:  # its row in the devices table says it too
            self._show(self.doctor_rows[:-1])
