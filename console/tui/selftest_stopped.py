"""How the Devices self-test row says a run stopped before its end: what stopped it and
when, the time said once (``by the e-stop at 23:32:34``; after a restart, from the kept
record, ``by the e-stop at 2026-11-30 23:32``)."""

from __future__ import annotations

import re

#: a time of day a record kept before its time was kept apart (``by the e-stop at
#: 23:32:34``, ``at 23:32:34: why``): left out, the record's own time said instead
_OLD_TIME = re.compile(r"^at \d\d:\d\d:\d\d: | at \d\d:\d\d:\d\d$")


def stopped_when(what: str, when: str) -> str:
    """``what`` stopped the run (``by the e-stop``, or the test's own reason) at
    ``when``, in one phrase."""
    return f"{what} at {when}" if what.startswith("by ") else f"at {when}: {what}"


def kept_stopped(kept: dict[str, str]) -> str:
    """A stopped run as kept (``console.runtime.selftest_last``: its ``line`` says what
    stopped it, its ``time`` when), in one phrase."""
    return stopped_when(_OLD_TIME.sub("", kept.get("line", "")), kept.get("time", ""))
