"""The last plan the gate passed, whoever sent it, as the kernel's ``scope`` reply says it
(``console.kernel.requests.last_plan``): checked on arrival like every reply."""

from __future__ import annotations

import math
import os
from dataclasses import dataclass
from typing import Any

#: what the reply may carry (longer lists or texts are not a plan's)
_MAX_ITEMS = 4096
_MAX_TEXT = 300
#: the module a demo's process runs (its command line names it)
DEMO_HOST = "console.runtime.demo_host"


@dataclass(frozen=True)
class KernelPlan:
    """A plan the gate started passing: ``who`` sent it (``this console``, ``the CLI
    (pid 1234)``), where it plays, its segments' first and last gate clocks."""

    job: int
    name: str
    who: str
    own: bool
    duration_s: float
    where: tuple[str, ...]
    segment_start: tuple[int, ...]
    segment_end: tuple[int, ...]
    done: bool
    error: str

    @property
    def key(self) -> tuple[str, int]:
        """The same plan in two replies has the same key."""
        return (self.who, self.job)


def who_sent(role: str, command: str, pid: int, own: bool) -> str:
    """Who sent a plan, in the operator's words."""
    if own:
        return "this console"
    if role == "console":
        return f"another console (pid {pid})"
    if role.startswith("demo "):  # the console's demo host (``console.runtime.demo_host``)
        return f"the {role[5:]} demo (pid {pid})"
    if DEMO_HOST in command:
        return f"a demo (pid {pid})"
    program = os.path.basename(command.split(" ", 1)[0]) if command else ""
    if program == "haptable":
        return f"the CLI (pid {pid})"
    return f"{program or 'a process'} (pid {pid})"


def _text(v: Any) -> str:
    if not isinstance(v, str):
        raise ValueError("not a text")
    return v[:_MAX_TEXT]


def _ints(v: Any) -> tuple[int, ...]:
    if not isinstance(v, list) or len(v) > _MAX_ITEMS or not all(type(x) is int for x in v):
        raise ValueError("not a list of whole numbers")
    return tuple(v)


def _int(v: Any) -> int:
    if type(v) is not int:
        raise ValueError("not a whole number")
    return v


def kernel_plan(raw: Any, own_client: int) -> KernelPlan | None:
    """``raw`` (a scope reply's ``last_plan``) checked; None when absent or malformed
    (the scope then says no plan, never a wrong one)."""
    if not isinstance(raw, dict):
        return None
    try:
        duration = raw["duration_s"]
        if not isinstance(duration, (int, float)) or not math.isfinite(duration):
            raise ValueError("duration_s")
        where = [_text(p) for p in raw["patches"]] if isinstance(raw["patches"], list) else None
        if where is None or len(where) > _MAX_ITEMS:
            raise ValueError("patches")
        if raw["screen"] is True:
            where.append("screen")
        client = _int(raw["client"])
        own = client == own_client
        return KernelPlan(
            job=_int(raw["job"]),
            name=_text(raw["name"]) or "plan",
            who=who_sent(_text(raw["role"]), _text(raw["command"]), _int(raw["pid"]), own),
            own=own,
            duration_s=float(duration),
            where=tuple(where),
            segment_start=_ints(raw["start"]),
            segment_end=_ints(raw["end"]),
            done=raw["done"] is True,
            error=_text(raw["error"]),
        )
    except (KeyError, ValueError, TypeError):
        return None
