"""The demo's outputs as the recorder sees them: every plan handed to the outputs (its
record and hash, when it was asked for, and the kernel's clocks its report got: the gate
clock of each segment's first and last sample, when its first sample reached the
driver, a refusal) and every relay request (pre-arm, disarm) and stream started.

``WatchedOutputs`` forwards everything to the outputs client unchanged (the kernel's
safety gate checks and plays it as before); it only notes what passed: what the client
sees. The kernel's own events (relay switches it made, e-stops, refusals) the recorder
pulls from the kernel itself (``console.core.gate_log``, ``gate_events``). Shared with
the studies' trial recordings, so it lives in the console (``console.core.plan_watch``,
through ``console.plugin_api``)."""

from __future__ import annotations

from typing import Any

from console.plugin_api import WatchedOutputs as NotedOutputs
from console.plugin_api import plan_line, report_clocks

__all__ = ["WatchedOutputs", "plan_line", "report_clocks"]


class WatchedOutputs(NotedOutputs):
    """``outputs`` with ``play``, ``prearm``, ``disarm``, ``stream`` noted to ``note``
    (``note(kind, record, report)``); every other member is the outputs' own."""

    def __getattr__(self, name: str) -> Any:
        return getattr(self._outputs, name)
