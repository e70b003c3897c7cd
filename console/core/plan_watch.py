"""What a run hands its outputs, as a recording keeps it: shared by the recorder
(``plugins/recording``) and the studies' trial recordings (``plugins/studies``).

``plan_hash`` (SHA-256 of a plan's samples, relays and labels), ``plan_record`` (a plan
as JSON values: name, hash, duration, segments, ``meta``), ``json_values`` (numbers,
arrays, tuples as JSON values, floats bit for bit), ``report_clocks`` (a ``PlayReport``'s
kernel clocks), ``plan_line`` and ``WatchedOutputs``: outputs whose ``play``, ``prearm``,
``disarm`` and ``stream`` are noted to a callback and forwarded unchanged (the kernel's
safety gate checks and plays them as before)."""

from __future__ import annotations

import hashlib
import time
from typing import Any

import numpy as np


def json_values(x: Any) -> Any:
    """Numbers, tuples, arrays and dicts as JSON values (floats kept bit for bit)."""
    if isinstance(x, dict):
        return {str(k): json_values(v) for k, v in x.items()}
    if isinstance(x, (list, tuple)):
        return [json_values(v) for v in x]
    if isinstance(x, np.ndarray):
        return json_values(x.tolist())
    if isinstance(x, (np.floating, float)):
        return float(x)
    if isinstance(x, (np.integer, int)) and not isinstance(x, bool):
        return int(x)
    if isinstance(x, (bool, np.bool_)):
        return bool(x)
    if x is None or isinstance(x, str):
        return x
    return repr(x)


def plan_hash(plan: Any) -> str:
    """SHA-256 of what a plan plays: rate, gap, and each segment's drives, relays and label."""
    h = hashlib.sha256()
    h.update(repr((int(plan.sample_rate_hz), float(plan.gap_s), plan.name)).encode())
    for seg in plan.segments:
        h.update(repr((sorted(seg.patches), bool(seg.screen), seg.label)).encode())
        for arr in (seg.piezo_v, seg.screen_v, *(seg.patch_v[p] for p in sorted(seg.patch_v))):
            h.update(np.ascontiguousarray(arr, dtype=np.float64).tobytes())
    return h.hexdigest()


def plan_record(plan: Any) -> dict:
    """A plan as a recording keeps it: name, hash, duration, relays and its ``meta``."""
    return {
        "name": plan.name,
        "hash": plan_hash(plan),
        "sample_rate_hz": int(plan.sample_rate_hz),
        "duration_s": float(plan.duration_s),
        "segments": [
            {"patches": sorted(s.patches), "screen": bool(s.screen), "n": s.n_samples}
            for s in plan.segments
        ],
        "meta": json_values(dict(plan.meta)),
    }


def report_clocks(report: Any) -> dict:
    """What a ``PlayReport`` says so far (JSON values): the gate clock of each segment's
    first and last sample, when its first sample reached the driver, an error."""
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


def plan_line(kind: str, rec: dict, report: Any) -> dict:
    """A noted output as a recording keeps it (a plan as ``plan_record``), JSON values."""
    rec = dict(rec)
    plan = rec.pop("plan", None)
    head = {"kind": kind, **(plan_record(plan) if plan is not None else {})}
    return {**head, **rec, **report_clocks(report)}


class WatchedOutputs:
    """``outputs``' ``play``, ``prearm``, ``disarm``, ``stream``, each noted to ``note``
    (``note(kind, record, report)``) after it was handed over. Only these four: a caller
    that needs the client's other members too (a demo) forwards them in a subclass
    (``plugins/recording/watch.py``)."""

    def __init__(self, outputs: Any, note: Any) -> None:
        self._outputs, self._note = outputs, note

    def play(self, plan: Any, **kw: Any) -> Any:
        """The outputs' ``play``; the plan is noted after it was handed over (its hash is
        taken later, off the caller's thread: nothing is added between decision and output)."""
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
