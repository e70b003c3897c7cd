"""The outputs kernel's own events as a recording keeps them: shared by the recorder
(``plugins/recording``) and the studies' trial recordings (``plugins/studies``).

The kernel's safety gate keeps an event for every e-stop, shutdown, fault, reset, relay
switch it made (those of the e-stop too, on every driver) and request it refused, each
with the gate's sample clock. ``GateLog(outputs)`` notes the kernel's clock when it is
made and ``pull()`` returns the events from that clock on not pulled before (the
recorder pulls from its writer thread and once at its end). ``EVENT_DTYPE`` is the
HDF5 dataset's row: ``t_s`` (monotonic seconds of the kernel's host), ``clock`` (gate
samples), ``kind``, ``message`` (UTF-8, cut at 240 bytes)."""

from __future__ import annotations

import logging
from collections.abc import Iterable
from typing import Any, Protocol, runtime_checkable

import numpy as np

from console.core.errors import SafetyRefusal

log = logging.getLogger("haptable.recording")

#: a row of a recording's ``gate_events`` dataset
EVENT_DTYPE = np.dtype([("t_s", "<f8"), ("clock", "<i8"), ("kind", "S16"), ("message", "S240")])
#: the dataset's name in both kinds of recording
DATASET = "gate_events"


@runtime_checkable
class ReportsGateEvents(Protocol):
    """Outputs that answer with the kernel's gate events and status (the kernel client)."""

    def events(self, since: int = 0) -> list: ...

    def status(self) -> dict[str, Any]: ...


def gate_clock(outputs: ReportsGateEvents) -> int:
    """The kernel's gate clock now (samples handed to the driver)."""
    return int(outputs.status()["gate"]["clock"])


def event_rows(events: Iterable[Any]) -> np.ndarray:
    """``GateEvent``\\ s as ``EVENT_DTYPE`` rows, in the order given."""
    evs = list(events)
    out = np.zeros(len(evs), EVENT_DTYPE)
    for i, e in enumerate(evs):
        msg = str(e.message).encode("utf-8")
        if len(msg) > 240:  # cut on a character boundary
            msg = msg[:240].decode("utf-8", "ignore").encode("utf-8")
        out[i] = (float(e.t_s), int(e.clock), str(e.kind).encode()[:16], msg)
    return out


def read_rows(rows: np.ndarray) -> list[dict[str, Any]]:
    """A ``gate_events`` dataset's rows as JSON values."""
    return [
        {
            "t_s": float(r["t_s"]),
            "clock": int(r["clock"]),
            "kind": bytes(r["kind"]).decode("utf-8", "replace"),
            "message": bytes(r["message"]).decode("utf-8", "replace"),
        }
        for r in rows
    ]


def counts_text(events: list[dict[str, Any]]) -> str:
    """``"5 gate events (2 relay switches, 1 e-stop, ...)"`` for a replay's line."""
    names = {
        "switch": "relay switch",
        "estop": "e-stop",
        "refused": "refusal",
        "fault": "fault",
        "reset": "reset",
        "shutdown": "shutdown",
    }
    n: dict[str, int] = {}
    for e in events:
        n[e["kind"]] = n.get(e["kind"], 0) + 1
    parts = []
    for kind, count in sorted(n.items(), key=lambda kv: (kv[0] != "switch", kv[0])):
        word = names.get(kind, kind)
        parts.append(
            f"{count} {word}{'es' if word.endswith('ch') else 's'}" if count != 1 else f"1 {word}"
        )
    head = f"{len(events)} gate event{'' if len(events) == 1 else 's'}"
    return f"{head} ({', '.join(parts)})" if parts else head


class GateLog:
    """The kernel's gate events from the clock it was made at (see the module); made on
    outputs that cannot report them (a test double, a session without a kernel
    client), it stays empty (``live`` False)."""

    def __init__(self, outputs: Any) -> None:
        self.live = isinstance(outputs, ReportsGateEvents)
        self._outputs = outputs
        self._seen: set[tuple] = set()
        self.error = ""
        self.since = 0
        if self.live:
            try:
                self.since = gate_clock(outputs)
            except (SafetyRefusal, KeyError, TypeError, OSError) as exc:
                self.live, self.error = False, str(exc)

    def clock_now(self) -> int:
        """The kernel's gate clock now (``since`` when it cannot say)."""
        if not self.live:
            return self.since
        try:
            return gate_clock(self._outputs)
        except (SafetyRefusal, KeyError, TypeError, OSError):
            return self.since

    def pull(self) -> np.ndarray:
        """The events not pulled before (``EVENT_DTYPE`` rows, in the kernel's order);
        none when the outputs went away (``error`` says why)."""
        if not self.live:
            return np.zeros(0, EVENT_DTYPE)
        try:
            evs = self._outputs.events(since=self.since)
        except (SafetyRefusal, OSError) as exc:
            if not self.error:
                log.warning("gate events not read: %s", exc)
            self.error = str(exc)
            return np.zeros(0, EVENT_DTYPE)
        new = []
        for e in evs:
            key = (e.t_s, e.clock, e.kind, e.message)
            if key not in self._seen:
                self._seen.add(key)
                new.append(e)
        return event_rows(new)
