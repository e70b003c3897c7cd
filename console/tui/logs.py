"""Log records while the console owns the terminal: into a file, into the log view
(``ctrl+l``: ``LogScreen``) and, for warnings and errors, as notifications (a stray write
to stderr would tear the screen).

What native code writes to stderr (OpenCV, PortAudio, libusb write to file descriptor 2
from C, past Python's ``sys.stderr``) goes there too: ``NativeStderr`` points fd 2 at a
pipe while the console runs and logs each line (logger ``haptable.native``); Textual
draws on a copy of the terminal's fd 2. Both are restored on exit.
"""

from __future__ import annotations

import collections
import contextlib
import logging
import os
import select
import sys
import threading
import time
from pathlib import Path
from typing import Any, TextIO

from textual.app import ComposeResult
from textual.binding import Binding
from textual.screen import ModalScreen
from textual.widgets import RichLog, Static

from console.files import paths
from console.tui.narrow import ConsoleFooter
from console.tui.safety_bar import SafetyBar
from console.tui.title_row import TitleRow
from console.tui.util import from_thread

#: the lines the log view keeps (the file keeps everything)
LOG_VIEW_LINES = 1000
NATIVE_LOGGER = "haptable.native"


#: the logger of details the log file keeps and the log view leaves out (tracebacks)
DETAILS_LOGGER = "haptable.console.details"


def log_path() -> Path:
    """``console.log`` in the state directory (``~/.local/state/haptable/console.log``)."""
    return paths.state_dir("console.log")


class NotifyHandler(logging.Handler):
    """WARNING and above as notifications; the same message at most every 5 s."""

    def __init__(self, app) -> None:
        super().__init__(logging.WARNING)
        self.app = app
        self._last: dict[str, float] = {}

    def emit(self, record: logging.LogRecord) -> None:
        if getattr(record, "on_screen", False):  # what the console said: shown already
            return
        msg = f"{record.name}: {record.getMessage()}"
        now = time.monotonic()
        if now - self._last.get(msg, -1e9) < 5.0:
            return
        self._last[msg] = now
        sev = "error" if record.levelno >= logging.ERROR else "warning"
        try:
            if threading.current_thread() is threading.main_thread():
                self.app.notify(msg, severity=sev, timeout=6, logged=True)
            else:
                from_thread(self.app, self.app.notify, msg, severity=sev, timeout=6, logged=True)
        except Exception:
            pass


class ViewHandler(logging.Handler):
    """Every record (INFO and above) as a line for the log view: kept in ``lines`` and
    written to the open ``LogScreen`` (from any thread); a record of ``DETAILS_LOGGER``
    (a failed worker's traceback: ``console.tui.workers``) is the log file's alone."""

    def __init__(self, app) -> None:
        super().__init__(logging.INFO)
        self.app = app
        self.lines: collections.deque[str] = collections.deque(maxlen=LOG_VIEW_LINES)
        self.setFormatter(logging.Formatter("%(asctime)s %(levelname)s %(name)s: %(message)s"))

    def emit(self, record: logging.LogRecord) -> None:
        if record.name == DETAILS_LOGGER:  # a traceback: the log file's alone
            return
        try:
            line = self.format(record)
        except Exception:
            return
        self.lines.append(line)
        try:
            if threading.current_thread() is threading.main_thread():
                self._show(line)
            else:
                from_thread(self.app, self._show, line)
        except Exception:
            pass

    def _show(self, line: str) -> None:
        screen = self.app.screen if self.app.is_running else None
        if isinstance(screen, LogScreen):
            screen.add(line)


class ReflowLog(RichLog):
    """A ``RichLog`` whose lines wrap again when its width changes (``RichLog`` wraps a
    line once, as it is written: a wider terminal kept the narrow wrap)."""

    def __init__(self, *args, **kw) -> None:
        super().__init__(*args, **kw)
        self._kept: list[str] = []
        self._wrapped_at = 0

    def show(self, lines: list[str]) -> None:
        self._kept = list(lines)
        self._rewrite()

    def add(self, line: str) -> None:
        self._kept.append(line)
        self._write(line)

    def _write(self, line: str) -> None:
        width = self.scrollable_content_region.width  # the view's, not the console's
        self.write(line, width=width if width > 0 else None)

    def _rewrite(self) -> None:
        self.clear()
        for line in self._kept:
            self._write(line)

    def on_resize(self, event) -> None:
        super().on_resize(event)
        width = event.size.width
        if width and self._wrapped_at and width != self._wrapped_at:
            self.set_timer(0.05, self._rewrite)  # once the new region is laid out
        self._wrapped_at = width or self._wrapped_at


class LogScreen(ModalScreen):
    """The console's log: its records and what drivers wrote to stderr (plain text)."""

    BINDINGS = [Binding("escape,q,ctrl+l", "dismiss", "close")]
    DEFAULT_CSS = """
    LogScreen { align: center top; }
    LogScreen > RichLog {
        width: 100%; height: 1fr; border: thick $accent; background: $panel;
        scrollbar-gutter: stable;  /* lines wrap to one width, scrollbar or not */
    }
    LogScreen > SafetyBar { dock: bottom; margin-bottom: 1; }  /* where the main one is */
    LogScreen > Static { width: 100%; height: auto; background: $panel; }
    LogScreen > #log-title { height: 1; background: $panel-darken-1; text-style: bold; }
    """

    def __init__(self, lines: list[str]) -> None:
        super().__init__()
        self.lines = lines

    def compose(self) -> ComposeResult:
        # the title row, as every screen has one: a notification shows over it (docked
        # at the top, ``console.tcss``), never over the log's key and file below it
        yield TitleRow(" HapTable log", id="log-title")  # whole words beside a toast
        # the key first; a long path wraps rather than cutting the words after it
        yield Static(f" escape closes · the log, also in {log_path()}", markup=False)
        # long lines wrap (a driver's message is read whole, no sideways scrolling);
        # plain text: brackets show as written; min_width=1: a line wraps at the view's
        # width (RichLog's default of 78 columns cut 2 at each wrap at 80 columns)
        yield ReflowLog(wrap=True, markup=False, highlight=False, auto_scroll=True, min_width=1)
        yield SafetyBar()  # the output state stays in view (the app keeps it current)
        yield ConsoleFooter()  # its keys and E-STOP, as on every screen

    def on_mount(self) -> None:
        log = self.query_one(ReflowLog)
        log.show(self.lines or ["(nothing logged yet)"])
        log.focus()

    def add(self, line: str) -> None:
        """A new record, shown at the end."""
        if not self.lines:
            self.query_one(ReflowLog).show([])  # "(nothing logged yet)" goes
        self.lines.append(line)
        self.query_one(ReflowLog).add(line)

    def leave_for_screen(self) -> bool:
        """An F-key closes the log to show its screen (``LeavesForScreen``)."""
        self.dismiss()
        return True


def view_handler() -> ViewHandler | None:
    """The log view's handler installed by ``capture_logs`` (None when not installed)."""
    for h in logging.getLogger().handlers:
        if isinstance(h, ViewHandler):
            return h
    return None


class NativeStderr:
    """File descriptor 2 into the log while the console owns the terminal.

    ``start()`` keeps a copy of the terminal's fd 2 (returned as a file: the screen is
    drawn there) and points fd 2 at a pipe; a thread logs each line written into it
    (logger ``haptable.native``: the first one as a warning, so the operator hears of
    it once, the others as information). A line holding one of the last lines logged is
    an echo (a handler writing to fd 2) or a repeat: counted in ``echoes``, not logged
    again. ``stop()`` puts the terminal back on fd 2 and logs what was still in the pipe.
    """

    def __init__(self, logger: str = NATIVE_LOGGER) -> None:
        self.log = logging.getLogger(logger)
        self.log.setLevel(logging.INFO)
        self.lines = 0
        self.echoes = 0  # lines dropped as echoes of what was just logged
        self._recent: collections.deque[str] = collections.deque(maxlen=32)
        self._saved: int | None = None
        self._terminal: TextIO | None = None
        self._thread: threading.Thread | None = None
        self._stopping = threading.Event()

    def start(self) -> TextIO:
        for stream in (sys.stderr, sys.__stderr__):
            with contextlib.suppress(Exception):
                stream.flush()
        self._saved = os.dup(2)
        read_fd, write_fd = os.pipe()
        os.dup2(write_fd, 2)
        os.close(write_fd)
        self._thread = threading.Thread(
            target=self._pump, args=(read_fd,), name="haptable-native-stderr", daemon=True
        )
        self._thread.start()
        self._terminal = os.fdopen(os.dup(self._saved), "w", buffering=1, errors="replace")
        return self._terminal

    def _pump(self, fd: int) -> None:
        """Log the pipe's lines until ``stop()``: then what is already in it, and end
        (not at the pipe's end of file: a process the console started, such as the
        multiprocessing resource tracker, inherits fd 2 and may hold the pipe open until
        after the console has gone)."""
        buf = b""
        with os.fdopen(fd, "rb", buffering=0) as pipe:
            while True:
                ready = select.select([fd], [], [], 0.1)[0]
                if not ready:
                    if self._stopping.is_set():
                        break
                    continue
                try:
                    chunk = pipe.read(4096)
                except OSError:
                    break
                if not chunk:
                    break
                buf += chunk
                *lines, buf = buf.split(b"\n")
                for line in lines:
                    self._emit(line)
        if buf:
            self._emit(buf)

    def _emit(self, raw: bytes) -> None:
        text = raw.decode(errors="replace").rstrip()
        if not text.strip():
            return
        # a handler that writes to fd 2 (a library's own StreamHandler) echoes what was
        # just logged back into the pipe: logging it again would never end
        if any(prev in text for prev in self._recent):
            self.echoes += 1
            return
        self._recent.append(text)
        self.lines += 1
        if self.lines == 1:
            self.log.warning("%s  (driver messages: ctrl+l shows the log)", text)
        else:
            self.log.info("%s", text)

    def stop(self, timeout_s: float = 2.0) -> None:
        if self._saved is None:
            return
        with contextlib.suppress(Exception):
            sys.stderr.flush()
        os.dup2(self._saved, 2)  # the terminal again; the pump logs what is left, then ends
        os.close(self._saved)
        self._saved = None
        self._stopping.set()
        if self._thread is not None:
            self._thread.join(timeout_s)
        if self._terminal is not None:
            self._terminal.close()
            self._terminal = None


def on_terminal(driver_class: type, terminal: TextIO) -> type:
    """``driver_class`` drawing on ``terminal`` (Textual's drivers write to
    ``sys.__stderr__``, which is the pipe while ``NativeStderr`` runs)."""

    class TerminalDriver(driver_class):  # type: ignore[misc, valid-type]
        def __init__(self, *args: Any, **kw: Any) -> None:
            super().__init__(*args, **kw)
            if hasattr(self, "_file"):
                self._file = terminal

    TerminalDriver.__name__ = f"{driver_class.__name__}OnTerminal"
    return TerminalDriver


def capture_logs(app) -> list[logging.Handler]:
    """Take stderr handlers off the root logger; log to a file, to the log view and to
    notifications. Returns the removed handlers (``release_logs`` puts them back)."""
    root = logging.getLogger()
    removed = [
        h
        for h in root.handlers
        if isinstance(h, logging.StreamHandler) and not isinstance(h, logging.FileHandler)
    ]
    for h in removed:
        root.removeHandler(h)
    try:
        path = log_path()
        path.parent.mkdir(parents=True, exist_ok=True)
        fh = logging.FileHandler(path)
        # one file for every console of the user: each line names its process
        fh.setFormatter(
            logging.Formatter("%(asctime)s [pid %(process)d] %(name)s %(levelname)s: %(message)s")
        )
        root.addHandler(fh)
    except OSError:
        pass
    root.addHandler(NotifyHandler(app))
    root.addHandler(ViewHandler(app))
    global _last_resort
    _last_resort = logging.lastResort
    logging.lastResort = None  # no fallback to stderr while the screen is ours
    return removed


_last_resort: logging.Handler | None = logging.lastResort


def release_logs(removed: list[logging.Handler]) -> None:
    root = logging.getLogger()
    for h in list(root.handlers):
        if isinstance(h, (NotifyHandler, ViewHandler, logging.FileHandler)):
            root.removeHandler(h)
            h.close()
    for h in removed:
        root.addHandler(h)
    logging.lastResort = _last_resort
