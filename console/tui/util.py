"""Small helpers shared by the panes."""

from __future__ import annotations

import os
from collections.abc import Callable
from typing import Any

from console.files.paths import shown_path


def short_path(p: str | os.PathLike) -> str:
    """``p`` as the screens show it: ``console.files.paths.shown_path`` (``~/...`` under
    the home folder, else absolute; a relative path as typed)."""
    return shown_path(p)


def from_thread(app: Any, fn: Callable[..., Any], *args: Any, **kw: Any) -> Any:
    """``app.call_from_thread(fn, ...)`` from a worker thread, or ``None`` once the app
    has stopped (a worker finishing while the console closes: its result is dropped,
    never raised into a console that is gone)."""
    try:
        return app.call_from_thread(fn, *args, **kw)
    except RuntimeError:  # the app is not running any more
        return None
