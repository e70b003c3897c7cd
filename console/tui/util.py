"""Small helpers shared by the panes."""

from __future__ import annotations

import os
from pathlib import Path


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
