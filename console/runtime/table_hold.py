"""The table's outputs held across processes: while a study run from a shell
(``haptable study run``, simulated or not) runs on a profile, the console of that
profile plays nothing (its screens' plays, auditions, test signals and demos are refused
naming the run, ``ConsoleSession.held_why``), and the console's own Studies run holds
the same file, so two runs never mix. A file in the private runtime directory says who
holds it and its pid; a holder that died holds nothing. The table's kernel holds a real
table's outputs too (``Client.hold``); this file is what a run on its own twin leaves
for the console to see. Every other shell command that plays on the profile's table
holds it the same way while its outputs are open (``Context.outputs``: ``haptable demo``,
``haptable play``, a measurement), named with its command, its pid and how to stop it
(``COMMAND_STOP``); a command that runs inside another's hold (a study run's outputs)
leaves that hold as it was."""

from __future__ import annotations

import contextlib
import json
import os
from collections.abc import Iterator
from pathlib import Path
from typing import Any

from console.core.errors import TableBusy
from console.kernel.private_dir import pid_alive, runtime_dir, write_private
from console.kernel.tables import table_key

#: a command refused because another process holds the table
BUSY = "{other} holds the outputs: stop it there first"
#: how a shell command holding the table is stopped, as the console's refusal says it
COMMAND_STOP = "ctrl+c in its shell stops it"


def _started(pid: int) -> str:
    """When process ``pid`` started (clock ticks since boot; "" where unknown): a
    holder's pid reused by a later process is not the holder."""
    try:
        with open(f"/proc/{pid}/stat", encoding="ascii") as f:
            return f.read().rsplit(")", 1)[1].split()[19]
    except (OSError, IndexError):
        return ""


def _hold(path: Path) -> dict[str, Any] | None:
    """The hold written in ``path`` when its process still runs (else None)."""
    try:
        held = json.loads(path.read_text(encoding="utf-8"))
        pid = int(held["pid"])
    except (OSError, ValueError, KeyError, TypeError):
        return None
    if not isinstance(held, dict) or not pid_alive(pid):
        return None
    started = str(held.get("started") or "")
    if started and _started(pid) not in ("", started):
        return None  # the holder died and its pid went to another process
    return held


def table_hold_file(profile: Any) -> Path:
    """Where the hold on ``profile``'s table is written (one per profile file)."""
    return runtime_dir() / f"table-hold-{table_key(profile.path)}.json"


def holder_in(path: Path) -> str | None:
    """Who, in another live process, holds what the hold file ``path`` guards."""
    held = _hold(path)
    if held is None or int(held["pid"]) == os.getpid():
        return None
    return str(held.get("who") or f"process {held['pid']}")


def stop_words_in(path: Path) -> str:
    """How the other process holding ``path`` is stopped, as it wrote it ("" if unsaid)."""
    held = _hold(path)
    if held is None or int(held["pid"]) == os.getpid():
        return ""
    return str(held.get("stop") or "")


@contextlib.contextmanager
def held_in(path: Path, who: str, busy: str, stop: str = "") -> Iterator[str]:
    """Hold ``path`` for this process as ``who`` (``TableBusy``: ``busy`` formatted with
    the other holder when another live process holds it); let go at the end, whatever
    ends it (a process killed leaves a file that holds nothing: its pid is dead).
    ``stop``: how the holder is stopped, for the refusals that name it. Inside this
    process's own hold it leaves that hold as it was (the outer one lets go)."""
    mine = _hold(path)
    if mine is not None and int(mine["pid"]) == os.getpid():
        yield str(mine.get("who") or who)
        return
    other = holder_in(path)
    if other is not None:
        raise TableBusy(busy.format(other=other))
    pid = os.getpid()
    write_private(
        path, json.dumps({"pid": pid, "who": who, "stop": stop, "started": _started(pid)})
    )
    try:
        yield who
    finally:
        with contextlib.suppress(OSError, ValueError, KeyError, TypeError):
            if json.loads(path.read_text(encoding="utf-8"))["pid"] == pid:
                path.unlink()


def table_holder(profile: Any) -> str | None:
    """Who, in another live process, holds ``profile``'s table for a run (else None)."""
    return holder_in(table_hold_file(profile))


def table_stop_words(profile: Any) -> str:
    """How the other process holding ``profile``'s table is stopped ("" if it said not)."""
    return stop_words_in(table_hold_file(profile))


def table_held(profile: Any, who: str, stop: str = "") -> contextlib.AbstractContextManager[str]:
    """``with table_held(profile, "a study run of exp1 (...)")``: hold ``profile``'s
    table for this process's run (``TableBusy`` naming the other run); ``stop``: how
    it is stopped (``COMMAND_STOP``), said by the console's refusals."""
    return held_in(table_hold_file(profile), who, BUSY, stop)


def refuse_if_held(profile: Any) -> None:
    """``TableBusy`` naming the other process holding ``profile``'s table (if one does)."""
    other = table_holder(profile)
    if other is not None:
        raise TableBusy(BUSY.format(other=other))


def command_words(argv: list[str]) -> str:
    """A shell command as a refusal names it: ``haptable demo knob (pid 4242)``."""
    words = " ".join(["haptable", *argv])
    if len(words) > 60:
        words = words[:59].rsplit(" ", 1)[0] + " …"
    return f"{words} (pid {os.getpid()})"
