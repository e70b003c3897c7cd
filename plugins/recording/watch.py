"""The demo's outputs as the recorder sees them: every plan handed to the outputs (its
record and hash, when it was asked for, and the kernel's clocks its report got: the gate
clock of each segment's first and last sample, when its first sample reached the
driver, a refusal) and every relay request (pre-arm, disarm) and stream started.

``WatchedOutputs`` forwards everything to the outputs client unchanged (the kernel's
safety gate checks and plays it as before); it only notes what passed. The kernel's
own events (gate refusals of blocks, relay switches it made) stay in its twin log: this
records what the client sees."""

from __future__ import annotations

import time
from typing import Any

from .decisions import plan_record


def plan_line(kind: str, rec: dict, report: Any) -> dict:
    """A noted output as the recording keeps it (a plan as ``plan_record``), JSON values."""
    rec = dict(rec)
    plan = rec.pop("plan", None)
    head = {"kind": kind, **(plan_record(plan) if plan is not None else {})}
    return {**head, **rec, **report_clocks(report)}


def report_clocks(report: Any) -> dict:
    """What a ``PlayReport`` says so far (JSON values)."""
    if report is None:
        return {"report": None}
    first = report.t_first_sample_s
    return {
        "segment_start": [int(x) for x in report.segment_start],
        "segment_end": [int(x) for x in report.segment_end],
        "t_first_sample_s": None if first is None else float(first),
        "error": str(report.error or ""),
        "done": bool(report.done.is_set()),
    }


class WatchedOutputs:
    """``outputs`` with ``play``, ``prearm``, ``disarm``, ``stream`` noted to ``note``
    (``note(kind, record, report)``); every other member is the outputs' own."""

    def __init__(self, outputs: Any, note: Any) -> None:
        self._outputs, self._note = outputs, note

    def __getattr__(self, name: str) -> Any:
        return getattr(self._outputs, name)

    def play(self, plan: Any, **kw: Any) -> Any:
        """The outputs' ``play``; the plan is noted after it was handed over (its hash is
        taken on the recorder's thread: nothing is added between decision and output)."""
        rec = {"plan": plan, "t_asked_s": time.monotonic()}
        try:
            report = self._outputs.play(plan, **kw)
        except Exception as exc:
            rec["refused"] = str(exc)
            self._note("plan", rec, None)
            raise
        self._note("plan", rec, report)
        return report

    def prearm(self, patches: frozenset[str], screen: bool) -> Any:
        rec = {"patches": sorted(patches), "screen": bool(screen), "t_asked_s": time.monotonic()}
        report = self._outputs.prearm(patches, screen)
        self._note("prearm", rec, report)
        return report

    def disarm(self) -> Any:
        rec = {"t_asked_s": time.monotonic()}
        report = self._outputs.disarm()
        self._note("disarm", rec, report)
        return report

    def stream(self, source: Any, name: str = "stream") -> Any:
        rec = {"name": str(name), "t_asked_s": time.monotonic()}
        report = self._outputs.stream(source, name)
        self._note("stream", rec, report)
        return report
