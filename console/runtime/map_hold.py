"""The vibration map held across processes: while a study run plays on a profile's map
(the Studies screen's or ``haptable study run``'s), no other process replaces the map
it plays on: the console's Vibration screen refuses to measure, load or import, and a
second run from a shell is refused (``TableBusy``, exit 5), each naming the run. A file
in the private runtime directory says who holds it and its pid; a holder that died
holds nothing."""

from __future__ import annotations

import contextlib
import hashlib
import json
import os
from collections.abc import Iterator
from pathlib import Path
from typing import Any

from console.core.errors import TableBusy
from console.kernel.private_dir import pid_alive, runtime_dir, write_private
from console.runtime.measured_map import measured_map_path


def hold_file(profile: Any) -> Path:
    """Where the hold on ``profile``'s measured map is written (one per map file)."""
    key = hashlib.sha1(str(measured_map_path(profile)).encode()).hexdigest()[:12]
    return runtime_dir() / f"map-hold-{key}.json"


def map_holder(profile: Any) -> str | None:
    """Who, in another live process, holds ``profile``'s map (else None)."""
    try:
        held = json.loads(hold_file(profile).read_text(encoding="utf-8"))
        pid = int(held["pid"])
    except (OSError, ValueError, KeyError, TypeError):
        return None
    if pid == os.getpid() or not pid_alive(pid):
        return None
    return str(held.get("who") or f"process {pid}")


@contextlib.contextmanager
def map_held(profile: Any, who: str) -> Iterator[str]:
    """``with map_held(profile, "P01's study run (...)")``: hold ``profile``'s map for
    this process's run (``TableBusy`` naming the other run when another process holds
    it); let go at the end, whatever ended the run."""
    other = map_holder(profile)
    if other is not None:
        raise TableBusy(f"{other} plays on the vibration map: stop it there first")
    path = hold_file(profile)
    write_private(path, json.dumps({"pid": os.getpid(), "who": who}))
    try:
        yield who
    finally:
        with contextlib.suppress(OSError, ValueError, KeyError, TypeError):
            if json.loads(path.read_text(encoding="utf-8"))["pid"] == os.getpid():
                path.unlink()
