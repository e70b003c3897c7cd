"""Quitting the console (``q``, ``ctrl+q``): at once when nothing runs; while work runs
or typed work is unsaved, only when asked twice within ``QUIT_CONFIRM_S``. The second
key is the confirmation's wherever the focus is: a text field never takes it (an
unsaved expression became ``... %q`` and the console stayed)."""

from __future__ import annotations

import asyncio
import contextlib
import threading
import time
from typing import Any

from rich.cells import cell_len
from textual import events

from console.tui.long_work import KeepsTypedWork, LongWork, RunsWork
from console.tui.said import log_said
from console.tui.toasts import TOAST_FRAME

#: the keys that quit (the app's ``q``, Textual's ``ctrl+q``)
QUIT_KEYS = frozenset({"q", "ctrl+q"})


def quit_question(head: str, busy: list[str], lost: list[str], room: int) -> tuple[str, str]:
    """The quit question in ``room`` columns and whole: ``head`` ("q again within 3 s
    quits"), then what it loses with its fix (first: what the operator can still keep),
    then what it stops; the parts that do not fit left for the log (``N more: ctrl+l``)."""
    parts = [f"losing {what}" for what in lost] + [f"stopping {what}" for what in busy]
    whole = f"{head}, {'; '.join(parts)}"
    for n in range(len(parts), 0, -1):
        left = len(parts) - n
        text = f"{head}, {'; '.join(parts[:n])}" + (f"; {left} more: ctrl+l" if left else "")
        if cell_len(text) <= room:
            return text, whole
    return f"{head}, {parts[0]}", whole


class ConfirmsQuit:
    """The app's quit action and its confirmation (a mixin of ``HapTableApp``)."""

    #: how long quitting waits for the session to close (a demo to stop, the projector,
    #: the camera) before it e-stops what is left and exits anyway
    QUIT_WAIT_S = 15.0
    #: while work runs, a second q (ctrl+q) within this many seconds quits
    QUIT_CONFIRM_S = 3.0
    _quit_asked: float = -1e9  # when q last asked to be pressed again

    session: Any
    screen_stack: Any
    _panes: dict

    def quit_pending(self) -> bool:
        """Whether a quit asked to be confirmed and its seconds are not over."""
        return time.monotonic() - self._quit_asked <= self.QUIT_CONFIRM_S

    async def confirm_quit(self, event: events.Key) -> bool:
        """A quit key while a quit waits for its confirmation: taken here (no field types
        it), the console quits. Returns whether the key was taken."""
        if event.key not in QUIT_KEYS or not self.quit_pending():
            return False
        event.stop()
        event.prevent_default()
        await self.action_quit()
        return True

    def work_under_way(self) -> list[str]:
        """What quitting would stop: a running demo, long work (a ``LongWork`` busy on
        any screen) and what panes say (``RunsWork``: a study run)."""
        out = []
        demo = self.session.demos.name if self.session.demos.run is not None else None
        if demo is not None:
            out.append(f"the {demo} demo")
        for screen in self.screen_stack:
            for lw in screen.query(LongWork):
                # the demo's start (``demo flow``) is the demo named above: said once
                if lw.busy and lw.name_running != f"demo {demo}":
                    out.append(lw.name_running)
        for pane in list(self._panes.values()):
            if isinstance(pane, RunsWork) and (what := pane.work_under_way()):
                out.append(what)
        return out

    def unsaved_work(self) -> list[str]:
        """Typed work quitting would lose (``KeepsTypedWork``: an unsaved signal)."""
        return [
            what
            for pane in list(self._panes.values())
            if isinstance(pane, KeepsTypedWork) and (what := pane.unsaved_work())
        ]

    async def action_quit(self) -> None:
        """Quit; while work runs (``work_under_way``) or typed work is unsaved
        (``unsaved_work``) only when asked twice."""
        busy, lost = self.work_under_way(), self.unsaved_work()
        now = time.monotonic()
        if (busy or lost) and now - self._quit_asked > self.QUIT_CONFIRM_S:
            self._quit_asked = now
            head = f"q again within {self.QUIT_CONFIRM_S:g} s quits"
            shown, whole = quit_question(head, busy, lost, self.size.width - TOAST_FRAME)
            log_said("toast", whole, "warning")  # whole in the log, fitted on the row
            self.notify(
                shown,
                severity="warning",
                timeout=self.QUIT_CONFIRM_S,
                question=True,  # a hidden screen's status never replaces it meanwhile
                logged=True,
            )
            return
        # the session closes while the screen still shows (the projector and the camera
        # take a moment to end): the title says so, then the console exits
        self.sub_title = "quitting: closing the outputs, projector and camera ..."
        await asyncio.to_thread(self._close_session)
        await super().action_quit()

    def _close_session(self) -> None:
        """``session.close`` within ``QUIT_WAIT_S``; what still runs after is e-stopped
        and left (the console exits anyway). Idempotent."""
        closer = threading.Thread(target=self.session.close, name="haptable-quit", daemon=True)
        closer.start()
        closer.join(self.QUIT_WAIT_S)
        if closer.is_alive():
            with contextlib.suppress(Exception):
                self.session.abandon("the console quit while its session was still closing")
