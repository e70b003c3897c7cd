"""The table's outputs held across processes: while a study run from a shell
(``haptable study run``, simulated or not) runs on a profile, the console of that
profile plays nothing (its screens' plays, auditions, test signals and demos are refused
naming the run, ``ConsoleSession.held_why``), and the console's own Studies run holds
the same file, so two runs never mix. A file in the private runtime directory says who
holds it and its pid; a holder that died holds nothing. The table's kernel holds a real
table's outputs too (``Client.hold``); this file is what a run on its own twin leaves
for the console to see."""

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


def table_hold_file(profile: Any) -> Path:
    """Where the hold on ``profile``'s table is written (one per profile file)."""
    return runtime_dir() / f"table-hold-{table_key(profile.path)}.json"


def holder_in(path: Path) -> str | None:
    """Who, in another live process, holds what the hold file ``path`` guards."""
    try:
        held = json.loads(path.read_text(encoding="utf-8"))
        pid = int(held["pid"])
    except (OSError, ValueError, KeyError, TypeError):
        return None
    if pid == os.getpid() or not pid_alive(pid):
        return None
    return str(held.get("who") or f"process {pid}")


@contextlib.contextmanager
def held_in(path: Path, who: str, busy: str) -> Iterator[str]:
    """Hold ``path`` for this process as ``who`` (``TableBusy``: ``busy`` formatted with
    the other holder when another live process holds it); let go at the end."""
    other = holder_in(path)
    if other is not None:
        raise TableBusy(busy.format(other=other))
    write_private(path, json.dumps({"pid": os.getpid(), "who": who}))
    try:
        yield who
    finally:
        with contextlib.suppress(OSError, ValueError, KeyError, TypeError):
            if json.loads(path.read_text(encoding="utf-8"))["pid"] == os.getpid():
                path.unlink()


def table_holder(profile: Any) -> str | None:
    """Who, in another live process, holds ``profile``'s table for a run (else None)."""
    return holder_in(table_hold_file(profile))


def table_held(profile: Any, who: str) -> contextlib.AbstractContextManager[str]:
    """``with table_held(profile, "a study run of exp1 (...)")``: hold ``profile``'s
    table for this process's run (``TableBusy`` naming the other run)."""
    return held_in(table_hold_file(profile), who, "{other} holds the outputs: stop it there first")
