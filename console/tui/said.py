"""One error, one place, and every message in the log.

The rule (README, "The console"): the outcome of a screen's own action (a key, a
command, a button, the work it started) is said on that screen's status line; a toast
is for what happens elsewhere or later (another screen's work, a driver, the e-stop key,
a screen's result that comes while the operator looks at another screen).

Whatever the console says, on a status line or as a toast, is also a record of logger
``haptable.console`` (the log view, ``ctrl+l``, and ``console.log``): a failure seen
once is still there after its line was replaced or its toast went. Such records are
marked ``on_screen``: ``console.tui.logs.NotifyHandler`` never shows them again.
"""

from __future__ import annotations

import logging
from typing import Any, Protocol, runtime_checkable

from textual.dom import DOMNode

__all__ = ["LOGGER", "ShowsWidgets", "log_said", "screen_name", "shows_now", "said_here"]

LOGGER = "haptable.console"
_log = logging.getLogger(LOGGER)
_log.setLevel(logging.INFO)  # the console's messages reach the log view at any root level

_LEVELS = {"information": logging.INFO, "warning": logging.WARNING, "error": logging.ERROR}


def log_said(where: str, text: str, severity: str = "error") -> None:
    """``text`` as said on the screen ``where`` (``status Vibration``, ``toast``) into the
    log, at the level of ``severity`` (``information``, ``warning``, ``error``)."""
    level = _LEVELS.get(severity, logging.INFO)
    _log.log(level, "%s: %s", where, " ".join(str(text).split()), extra={"on_screen": True})


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
    (``HapTableApp.shows``)."""

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
    if not shows_now(widget):
        widget.app.notify(f"{where}: {text}", severity=severity, timeout=8, logged=True)
