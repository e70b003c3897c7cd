"""Log records while the console owns the terminal: into a file and, for warnings and
errors, as notifications (a stray write to stderr would tear the screen)."""

from __future__ import annotations

import logging
import threading
import time
from pathlib import Path

from console import paths


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
        msg = f"{record.name}: {record.getMessage()}"
        now = time.monotonic()
        if now - self._last.get(msg, -1e9) < 5.0:
            return
        self._last[msg] = now
        sev = "error" if record.levelno >= logging.ERROR else "warning"
        try:
            if threading.current_thread() is threading.main_thread():
                self.app.notify(msg, severity=sev, timeout=6)
            else:
                self.app.call_from_thread(self.app.notify, msg, severity=sev, timeout=6)
        except Exception:
            pass


def capture_logs(app) -> list[logging.Handler]:
    """Take stderr handlers off the root logger; log to a file and to notifications.
    Returns the removed handlers (``release_logs`` puts them back)."""
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
        fh.setFormatter(logging.Formatter("%(asctime)s %(name)s %(levelname)s: %(message)s"))
        root.addHandler(fh)
    except OSError:
        pass
    root.addHandler(NotifyHandler(app))
    logging.lastResort = None  # no fallback to stderr while the screen is ours
    return removed


def release_logs(removed: list[logging.Handler]) -> None:
    root = logging.getLogger()
    for h in list(root.handlers):
        if isinstance(h, (NotifyHandler, logging.FileHandler)):
            root.removeHandler(h)
            h.close()
    for h in removed:
        root.addHandler(h)
