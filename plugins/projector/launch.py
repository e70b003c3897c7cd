"""How the console starts this projector: the command its supervisor runs.

Registered through ``haptable_register_projectors`` as ``moderngl``; the process is
``python -m plugins.projector`` (``haptable projector`` without the full console start-up)
serving the link on the socket the console gives it.
"""

from __future__ import annotations

import sys
from collections.abc import Iterable
from pathlib import Path
from typing import Any

from console.plugin_api.runtime import ProjectorLaunch

NAME = "moderngl"
DESCRIPTION = "full-screen pyglet + moderngl window, or offscreen through EGL (headless)"


def projector_command(
    socket_path: Path,
    *,
    profile_path: Path | None = None,
    headless: bool = False,
    extra: Iterable[str] = (),
) -> list[str]:
    """The command line of a supervised projector."""
    cmd = [sys.executable, "-m", "plugins.projector", "--socket", str(socket_path)]
    if profile_path is not None:
        cmd += ["--profile", str(profile_path)]
    if headless:
        cmd.append("--headless")
    return cmd + list(extra)


def launch(
    profile: Any,
    *,
    socket_path: Path,
    headless: bool = False,
    extra: Iterable[str] = (),
) -> ProjectorLaunch:
    """The registered factory: this projector for ``profile``, serving ``socket_path``."""
    path = getattr(profile, "path", None)
    return ProjectorLaunch(
        projector_command(socket_path, profile_path=path, headless=headless, extra=extra)
    )
