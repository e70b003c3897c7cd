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


@dataclass(frozen=True)
class PlayOutcome:
    """What became of a plan the console asked to play (``ConsoleSession.play``): a
    status line says what happened from this, never from having asked.

    ``refused``: why it never started ("" when it did); ``started``: its first segment
    reached the outputs; ``stopped``: why it ended early once started (an e-stop);
    ``played``: it played through."""

    name: str
    started: bool = False
    played: bool = False
    refused: str = ""
    stopped: str = ""

    @property
    def estop_refused(self) -> bool:
        return self.refused.startswith(ESTOP_REFUSAL)

    @property
    def how_it_stopped(self) -> str:
        """How a started play ended early, as a line says it: ``stopped by the e-stop
        (...)``, ``stopped: no end reported in time`` or ``stopped``; one ``stopped``,
        however the reason came worded (the kernel's ``stopped: REASON``)."""
        why = stop_reason(self.stopped)
        if not why:
            return "stopped"
        return f"stopped by {why}" if why.startswith("the ") else f"stopped: {why}"


def stop_reason(text: str) -> str:
    """``text`` without the ``stopped:``/``stopped by`` it may already start with (a
    reason composed twice said "stopped by stopped: haptable estop")."""
    why = text.strip()
    while True:
        for head in ("stopped:", "stopped by ", "stopped"):
            if why.startswith(head):
                why = why[len(head) :].strip()
                break
        else:
            return why


#: how a request refused before it started because of the e-stop is worded (screens
#: clear such refusals when the e-stop is reset)
ESTOP_REFUSAL = "refused: e-stop active"
ESTOP_FIX = "ctrl+r resets"


def estop_refusal(reason: str = "") -> str:
    """A request the e-stop refused, in the console's words, its key first (the CLI's
    words name `haptable reset`: ``console.kernel.client.latched_line``):
    ``refused: e-stop active (operator e-stop (console)), ctrl+r resets``."""
    reason = " ".join(reason.split())
    return f"{ESTOP_REFUSAL} ({reason}), {ESTOP_FIX}" if reason else f"{ESTOP_REFUSAL}, {ESTOP_FIX}"
