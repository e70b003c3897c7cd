"""The vibration map held across processes: while a study run plays on a profile's map
(the Studies screen's or ``haptable study run``'s), no other process replaces the map
it plays on: the console's Vibration screen refuses to measure, load or import, and a
second run from a shell is refused (``TableBusy``, exit 5), each naming the run. A file
in the private runtime directory says who holds it and its pid; a holder that died
holds nothing."""

from __future__ import annotations

import contextlib
import hashlib
from pathlib import Path
from typing import Any

from console.kernel.private_dir import runtime_dir
from console.runtime.measured_map import measured_map_path
from console.runtime.table_hold import held_in, holder_in


def hold_file(profile: Any) -> Path:
    """Where the hold on ``profile``'s measured map is written (one per map file)."""
    key = hashlib.sha1(str(measured_map_path(profile)).encode()).hexdigest()[:12]
    return runtime_dir() / f"map-hold-{key}.json"


def map_holder(profile: Any) -> str | None:
    """Who, in another live process, holds ``profile``'s map (else None)."""
    return holder_in(hold_file(profile))


def map_held(profile: Any, who: str) -> contextlib.AbstractContextManager[str]:
    """``with map_held(profile, "P01's study run (...)")``: hold ``profile``'s map for
    this process's run (``TableBusy`` naming the other run when another process holds
    it); let go at the end, whatever ended the run."""
    return held_in(
        hold_file(profile), who, "{other} plays on the vibration map: stop it there first"
    )
