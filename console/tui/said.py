"""One error, one place, and every message in the log.

The rule (README, "The console"): the outcome of a screen's own action (a key, a
command, a button, the work it started) is said on that screen's status line; a toast
is for what happens elsewhere or later (another screen's work, a driver, the e-stop key,
a screen's result that comes while the operator looks at another screen), but never over
the e-stop's own notification (a hidden screen's echo of the e-stop or its reset is in the
log only, whenever it comes: ``echoes_estop``).

Whatever the console says, on a status line or as a toast, is also a record of logger
``haptable.console`` (the log view, ``ctrl+l``, and ``console.log``): a failure seen
once is still there after its line was replaced or its toast went. Such records are
marked ``on_screen``: ``console.tui.logs.NotifyHandler`` never shows them again.
A status line's every new message is logged once, when it changes (``log_status``: what
the operator read, in order, to reconstruct a session): the line standing when a screen
shows again (or redraws) is not news and is never logged again; nor are its ticks: a
line that differs from the last one logged for its screen in its numbers only
(``measuring 34 %, 12 s left``) is logged again only after ``PROGRESS_S``. One event
is one record at one level: a line said as a warning or an error (``said_here``) is not
also logged as information.
"""

from __future__ import annotations

import logging
import re
import threading
import time
from typing import Any, Protocol, runtime_checkable

from textual.dom import DOMNode

__all__ = [
    "LOGGER",
    "PROGRESS_S",
    "ShowsWidgets",
    "log_said",
    "log_status",
    "screen_name",
    "shows_now",
    "said_here",
    "echoes_estop",
    "status_said",
]

LOGGER = "haptable.console"
_log = logging.getLogger(LOGGER)
_log.setLevel(logging.INFO)  # the console's messages reach the log view at any root level

_LEVELS = {"information": logging.INFO, "warning": logging.WARNING, "error": logging.ERROR}


def log_said(where: str, text: str, severity: str = "error") -> None:
    """``text`` as said on the screen ``where`` (``status Vibration``, ``toast``) into the
    log, at the level of ``severity`` (``information``, ``warning``, ``error``)."""
    level = _LEVELS.get(severity, logging.INFO)
    _log.log(level, "%s: %s", where, " ".join(str(text).split()), extra={"on_screen": True})


#: a status line differing from the last one logged for its screen in its numbers only
#: is progress: logged again after this many seconds (a tick of work, not news)
PROGRESS_S = 30.0
_NUMBER = re.compile(r"\d+(?:[.,]\d+)*")
_last_status: dict[str, tuple[str, str, float]] = {}  # where -> (line, shape, when logged)
_status_lock = threading.Lock()


def log_status(where: str, text: str, now: float | None = None) -> bool:
    """A screen's status line, now ``text``, into the log as information (``status
    Vibration: point 51 played``), unless it is the last line logged for ``where`` again
    (at any time: a redraw, the screen shown again) or that line with other numbers
    within ``PROGRESS_S`` (a tick). Returns whether it was logged."""
    line = " ".join(str(text).split())
    if not line:
        return False
    if not _remember(where, line, now, repeat_ok=False):
        return False
    log_said(f"status {where}", line, "information")
    return True


def _remember(where: str, line: str, now: float | None, repeat_ok: bool) -> bool:
    """``line`` as the last one logged for ``where``; False (nothing changed) unless
    ``repeat_ok`` when it is the last one again, or that one with other numbers within
    ``PROGRESS_S``."""
    now = time.monotonic() if now is None else now
    shape = _NUMBER.sub("#", line)
    with _status_lock:
        last = _last_status.get(where)
        same = last is not None and (
            last[0] == line or (last[1] == shape and now - last[2] < PROGRESS_S)
        )
        if same and not repeat_ok:
            return False
        _last_status[where] = (line, shape, now)
    return True


def screen_name(widget: DOMNode, default: str) -> str:
    """The name of the screen or panel ``widget`` is on, as the log names it (its
    nearest ``...Pane`` or ``...Panel``: ``GesturesPanel`` is ``Gestures``), else
    ``default``."""
    for node in widget.ancestors_with_self:
        cls = type(node).__name__
        for tail in ("Panel", "Pane"):
            if cls.endswith(tail) and len(cls) > len(tail):
                return cls.removesuffix(tail)
    return default


@runtime_checkable
class ShowsWidgets(Protocol):
    """An app that knows whether the operator sees a widget's screen now
    (``HapTableApp.shows``); its ``notify`` takes ``hidden_screen=True`` for a hidden
    screen's status (``console.tui.toasts.NewestToastOnly``)."""

    def shows(self, widget: Any) -> bool: ...


def shows_now(widget: Any) -> bool:
    """Whether the operator sees ``widget``'s screen now (an app that cannot tell: yes)."""
    app = widget.app
    return app.shows(widget) if isinstance(app, ShowsWidgets) else True


def said_here(widget: Any, where: str, text: str, severity: str = "error") -> None:
    """A screen's own outcome ``text``, already shown on ``widget`` (its status line):
    logged; a toast too when the operator does not see that screen now (work that
    finished after they moved on)."""
    log_said(f"status {where}", text, severity)
    _remember(where, " ".join(str(text).split()), None, repeat_ok=True)
    if not shows_now(widget) and not echoes_estop(text):  # the e-stop's own says it
        app = widget.app
        app.notify(
            f"{where}: {text}", severity=severity, timeout=8, logged=True, hidden_screen=True
        )


def echoes_estop(text: str) -> bool:
    """Whether a screen's line ``text`` speaks of the e-stop or its reset: from a hidden
    screen it is an echo of the e-stop's own notification (or the reset's) and goes to
    the log only, whenever it comes (one after the reset said a latched e-stop on the
    title row under an idle safety bar)."""
    return "e-stop" in str(text).lower()


def status_said(widget: Any, where: str, text: str, severity: str = "information") -> None:
    """A screen's status line now says ``text``: a warning or an error as ``said_here``
    (logged, a toast when the screen is not in view); information into the log only,
    news and not ticks (``log_status``)."""
    if severity in ("warning", "error"):
        said_here(widget, where, text, severity)
    else:
        log_status(where, text)
