"""Small helpers shared by the panes."""

from __future__ import annotations

import os
from collections.abc import Callable
from pathlib import Path
from typing import Any


def short_path(p: str | os.PathLike) -> str:
    """``p`` relative to the working folder when inside it, else with ``~``, else as is."""
    path = Path(p)
    try:
        return str(path.resolve().relative_to(Path.cwd().resolve()))
    except ValueError:
        pass
    try:
        return "~/" + str(path.resolve().relative_to(Path.home().resolve()))
    except ValueError:
        return str(path)


def from_thread(app: Any, fn: Callable[..., Any], *args: Any, **kw: Any) -> Any:
    """``app.call_from_thread(fn, ...)`` from a worker thread, or ``None`` once the app
    has stopped (a worker finishing while the console closes: its result is dropped,
    never raised into a console that is gone)."""
    try:
        return app.call_from_thread(fn, *args, **kw)
    except RuntimeError:  # the app is not running any more
        return None
