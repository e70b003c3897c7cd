"""What the console session reports to the screens that observe it.

Each event names its ``topic`` (``outputs``, ``camera``, ``calibration``, ``vibration``,
``demo``, ``projector``) and, where it has one, the ``name`` of the thing it concerns (a
demo, a scene, a job). Events are emitted from any thread; subscribers must not block.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Any


@dataclass(frozen=True)
class SessionEvent:
    topic: str
    name: str = ""


@dataclass(frozen=True)
class Started(SessionEvent):
    """Something began (outputs opened, a demo runs, a scene shows)."""

    detail: str = ""


@dataclass(frozen=True)
class Stopped(SessionEvent):
    """Something ended; ``reason`` says how (``stopped``, ``cancelled``, an error ...)."""

    reason: str = ""


@dataclass(frozen=True)
class Snapshot(SessionEvent):
    """The newest state of something running (JSON-like values)."""

    data: dict[str, Any] = field(default_factory=dict)


@dataclass(frozen=True)
class Progress(SessionEvent):
    """Long work advanced: ``fraction`` in [0, 1] (None: unknown), ``text`` for the operator."""

    fraction: float | None = None
    text: str = ""


@dataclass(frozen=True)
class Failed(SessionEvent):
    """Something was refused or failed: ``message`` is one line for the operator."""

    message: str = ""
    severity: str = "error"
