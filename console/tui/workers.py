"""The console's workers, one rule for a failure nobody expected.

Every worker the console starts (``work`` in place of Textual's, ``run_worker`` in place
of ``Widget.run_worker``; tests/console/test_worker_rule.py holds console/ and plugins/
to it) runs its function guarded: an exception it did not handle itself is a bug, and
Textual's default for it (the app exits) left the operator without a console. Instead:

- every output this console plays stops by the safety kernel's normal stop (``release``:
  ramped down, queue dropped; no e-stop latch), so no play is left running;
- the traceback goes to the session's log file (``console.tui.logs.log_path``), not to
  the screen;
- one line, ``<what> failed: <Type: message> (details in <log>); the console goes on``,
  shows on the screen that started the work (a line of its own at its top) and in the
  log (ctrl+l), a toast too when that screen is not in view;
- the console stays up, the e-stop with it.
"""

from __future__ import annotations

import functools
import inspect
import logging
import threading
import traceback
from collections.abc import Callable
from typing import Any

from textual import work as _textual_work
from textual.widgets import Static

from console.tui.logs import DETAILS_LOGGER, log_path
from console.tui.said import log_said, said_here, screen_name
from console.tui.util import from_thread

#: the traceback of a failed worker: the log file only (``ViewHandler`` skips it)
DETAILS = logging.getLogger(DETAILS_LOGGER)
#: the class of the failure's line on its screen
FAILED_CLASS = "worker-failed"


def failed_line(what: str, exc: BaseException) -> str:
    """The one line a failed worker says (the message's first line: the rest is in the
    log file with the traceback)."""
    msg = next(iter(str(exc).splitlines()), "")
    return (
        f"{what} failed: {type(exc).__name__}: {msg} (details in {log_path()}); the console goes on"
    )


def _what(fn: Callable[..., Any]) -> str:
    """A worker function's name as the line says it (``_build_tables``: build tables,
    ``action_doctor``: doctor)."""
    name = fn.__name__.strip("_").removeprefix("action_").removesuffix("_worker")
    return name.replace("_", " ") or "work"


def contain(app: Any, what: str, exc: BaseException) -> str:
    """In the failed work's thread: the traceback to the log file, this console's
    outputs stopped by the kernel's normal stop; the line to say (``failed_line``)."""
    text = failed_line(what, exc)
    details = "".join(traceback.format_exception(exc))
    DETAILS.error("%s\n%s", text, details, extra={"on_screen": True})
    try:
        out = app.session.outputs  # the console's app (HapTableApp)
    except AttributeError:  # an app without a session (a widget's test host)
        out = None
    if out is not None and not out.lost:
        try:  # the kernel's normal stop: what this console plays ramps down
            out.release(f"{what} failed")
        except Exception:  # noqa: BLE001 - the line is said whatever the outputs do
            DETAILS.exception("stopping the outputs after %s", text, extra={"on_screen": True})
    return text


def worker_failed(node: Any, what: str, exc: BaseException) -> None:
    """In the failed worker's thread: ``contain`` it, then show the line on ``node``'s
    screen (the UI thread does that part)."""
    app = node.app
    text = contain(app, what, exc)
    if threading.get_ident() == app._thread_id:  # an async worker: the app's thread
        show_failure(node, text)
    else:
        from_thread(app, show_failure, node, text)


def _screen_of(node: Any) -> Any:
    """The pane or panel ``node`` is on (None: the app's own work)."""
    for n in node.ancestors_with_self:
        if type(n).__name__.endswith(("Pane", "Panel")):
            return n
    return None


def show_failure(node: Any, text: str) -> None:
    """On the UI thread: ``text`` on its screen's line of its own, logged (a toast
    when the screen is not in view); the app's own work: a toast."""
    app = node.app
    pane = _screen_of(node)
    if pane is None or not pane.is_attached:
        log_said("toast", text, "error")
        app.notify(text, severity="error", timeout=15, logged=True)
        return
    lines = pane.query(f"Static.{FAILED_CLASS}")
    if lines:
        lines.first(Static).update(text)
    else:
        line = Static(text, markup=False, classes=FAILED_CLASS)
        line.styles.color = "red"
        line.styles.height = "auto"
        pane.mount(line, before=0) if pane.children else pane.mount(line)
    said_here(pane, screen_name(pane, "console"), text, "error")


def guarded(node: Any, fn: Callable[..., Any], what: str) -> Callable[..., Any]:
    """``fn`` whose unexpected exception is said by the rule (``worker_failed``)
    instead of raised into Textual."""
    if inspect.iscoroutinefunction(fn):

        @functools.wraps(fn)
        async def run_async(*args: Any, **kw: Any) -> Any:
            try:
                return await fn(*args, **kw)
            except Exception as exc:  # noqa: BLE001 - the rule: said, never the app's end
                worker_failed(node, what, exc)
                return None

        return run_async

    @functools.wraps(fn)
    def run(*args: Any, **kw: Any) -> Any:
        try:
            return fn(*args, **kw)
        except Exception as exc:  # noqa: BLE001 - the rule: said, never the app's end
            worker_failed(node, what, exc)
            return None

    return run


def work(method: Callable[..., Any] | None = None, *, what: str = "", **options: Any) -> Any:
    """Textual's ``@work`` under the rule: ``what`` names the work in the failure's line
    (default: the method's name, ``_build_tables`` is "build tables")."""

    def decorate(fn: Callable[..., Any]) -> Any:
        name = what or _what(fn)

        if inspect.iscoroutinefunction(fn):

            @functools.wraps(fn)
            async def method_async(self: Any, *args: Any, **kw: Any) -> Any:
                return await guarded(self, fn, name)(self, *args, **kw)

            body: Callable[..., Any] = method_async
        else:

            @functools.wraps(fn)
            def method_sync(self: Any, *args: Any, **kw: Any) -> Any:
                return guarded(self, fn, name)(self, *args, **kw)

            body = method_sync
        return _textual_work(body, **{**options, "exit_on_error": False})

    return decorate if method is None else decorate(method)


def run_worker(node: Any, fn: Callable[..., Any], *, what: str = "", **options: Any) -> Any:
    """``node.run_worker(fn, ...)`` under the rule (``what``: as ``work``'s)."""
    name = what or options.get("name") or _what(fn)
    return node.run_worker(guarded(node, fn, name), **{**options, "exit_on_error": False})
