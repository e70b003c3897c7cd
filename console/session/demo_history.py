"""A demo run's latency as the console polled it (``DemoControl.poll``): the p50 of each
stage per poll, for the Latency screen's sparklines whether or not it showed during the
run, and when the run ended (its numbers stay, marked as the finished run's)."""

from __future__ import annotations

import time
from collections import deque
from typing import Any

#: p50 values kept per stage (a poll each 0.25 s: two minutes)
HISTORY = 500


def stage_p50s(latency: dict[str, Any]) -> dict[str, float]:
    """The p50 in ms of each stage of a monitor snapshot, by the monitor's keys (its
    stages, ``capture_to_arrival``, ``end_to_end``); stages with no number left out."""
    stages = dict(latency.get("stages") or {})
    for key in ("capture_to_arrival", "end_to_end"):
        stages[key] = latency.get(key) or {}
    out = {}
    for key, d in stages.items():
        p50 = (d or {}).get("p50_ms")
        if p50 is not None and p50 == p50:
            out[key] = float(p50)
    return out


class RunHistory:
    """``begin(name)`` at a start, ``add(snapshot)`` per poll, ``end()`` when it ended."""

    def __init__(self, size: int = HISTORY) -> None:
        self.size = size
        self.name: str | None = None
        self.ended_at: float | None = None  # wall clock (time.time) of its end
        self.p50: dict[str, deque] = {}

    def begin(self, name: str) -> None:
        self.name, self.ended_at, self.p50 = name, None, {}

    def add(self, snap: dict[str, Any]) -> None:
        for key, v in stage_p50s(snap.get("latency") or {}).items():
            self.p50.setdefault(key, deque(maxlen=self.size)).append(v)

    def end(self) -> None:
        if self.name is not None and self.ended_at is None:
            self.ended_at = time.time()

    def values(self, key: str) -> list[float]:
        return list(self.p50.get(key, ()))
