"""The session's starts and stops in the console's log (``ctrl+l``, ``console.log``):
with the status lines and toasts (``console.tui.said``) an operator can reconstruct a
session from it: e-stops and resets, outputs opened and lost, demos, scenes,
measurements, study runs. Snapshots and progress are ticks, not logged; nor is the
camera starting and stopping as the screens that watch it show and hide."""

from __future__ import annotations

import time

from console.session.events import SessionEvent, Started, Stopped
from console.tui.said import log_said

__all__ = ["event_line", "log_event"]

#: the camera stopping for this reason follows the screens: not news
QUIET_STOPS = {("camera", "nobody watches")}
#: a ``Stopped`` reason saying what became of the work, not that it stopped: logged as
#: it is (``calibration saved: PATH``; refused: it never started)
OUTCOMES = ("refused: ", "saved: ")
#: the same line again this soon is one event heard twice (an e-stop latched by the
#: console is reported by the session and again by the table's kernel)
ECHO_S = 2.0
_last: list = [None, -1e9]  # the last line logged, when


def event_line(ev: SessionEvent) -> tuple[str, str] | None:
    """``(line, severity)`` an event says in the log, or None (a tick, or the camera
    following the screens)."""
    name = f" {ev.name}" if ev.name else ""
    if ev.topic == "estop":
        if isinstance(ev, Stopped):
            return f"E-STOP{name}: {ev.reason}".rstrip(": "), "warning"
        if isinstance(ev, Started):
            return f"e-stop reset{name}: {ev.detail}".rstrip(": "), "information"
        return None
    if isinstance(ev, Started):
        if ev.topic == "camera":
            return None
        return f"{ev.topic}{name} {ev.detail or 'started'}", "information"
    if isinstance(ev, Stopped):
        if (ev.topic, ev.reason) in QUIET_STOPS:
            return None
        if ev.reason.startswith(OUTCOMES):  # not a stop: what became of it
            return f"{ev.topic}{name} {ev.reason}", "information"
        return f"{ev.topic}{name} stopped: {ev.reason or 'ended'}", "information"
    return None


def log_event(ev: SessionEvent, now: float | None = None) -> bool:
    """``ev`` into the log as ``session: ...`` when it is news (``event_line``) and not
    the same line again within ``ECHO_S``; returns whether it was logged."""
    said = event_line(ev)
    now = time.monotonic() if now is None else now
    if said is None or (said[0] == _last[0] and now - _last[1] < ECHO_S):
        return False
    _last[:] = [said[0], now]
    log_said("session", *said)
    return True
