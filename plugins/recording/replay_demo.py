"""Replay a recorded demo run through the demo itself: the recording's frames at their
recorded pace through the registered demo (vision, gestures, the scene, its effect and
plans, handed to the profile's outputs behind the safety gate as any run's are), each
frame held until the loop's queue is empty (no frame dropped however busy the machine).

Compared: every frame's decisions (``decisions.VISION_KEYS``) and the plans the demo
handed to the outputs, in order (name and hash of their samples)."""

from __future__ import annotations

import time
from pathlib import Path
from typing import Any

from console.plugin_api import UserError, counted, gate_events_text

from .camera import ReplayCamera
from .decisions import compare, frame_decisions
from .reader import open_recording
from .replay import _events, _versions_note
from .watch import WatchedOutputs, plan_line


class Comparer:
    """A frame sink comparing each frame with the recording, and noting the plans the
    replayed demo hands its outputs (``watch_outputs``)."""

    def __init__(self, rec: Any) -> None:
        self.rec = rec
        self.by_seq = {int(s): k for k, s in enumerate(rec.seq)}
        self.first_diff: str | None = None
        self.frames = 0
        self.plans: list[dict] = []

    def __call__(self, frame: Any, work: dict) -> None:
        self.frames += 1
        k = self.by_seq.get(int(frame.seq))
        if self.first_diff is not None or k is None:
            return
        self.first_diff = compare(frame.seq, self.rec.decisions(k), frame_decisions(work))

    def watch_outputs(self, outputs: Any) -> WatchedOutputs:
        return WatchedOutputs(outputs, self._note)

    def _note(self, kind: str, rec: dict, report: Any) -> None:
        if kind == "plan":
            self.plans.append(plan_line(kind, rec, None))

    def close(self) -> None:
        pass


def first_plan_difference(recorded: list[dict], replayed: list[dict]) -> str | None:
    for i, (a, b) in enumerate(zip(recorded, replayed, strict=False)):
        if (a["name"], a["hash"]) != (b["name"], b["hash"]):
            return (
                f"plan {i + 1}: recorded {a['name']!r} ({a['hash'][:12]}) vs replayed "
                f"{b['name']!r} ({b['hash'][:12]})"
            )
    if len(recorded) != len(replayed):
        return f"plans: {len(recorded)} recorded vs {len(replayed)} replayed"
    return None


def replay_demo(path: str | Path, ctx: Any) -> tuple[bool, str]:
    """(same, one line) for a recorded demo run replayed through its demo."""
    with open_recording(path) as rec:
        name = rec.attrs.get("demo") or ""
        if not name:
            raise UserError(f"recording {rec.path}: no demo recorded in it; use --vision-only")
        if rec.n_frames == 0:
            raise UserError(f"recording {rec.path}: no frame was recorded; record a longer run")
        cam = ReplayCamera(rec, realtime=True)
        sink = Comparer(rec)
        recorded_plans = [p for p in rec.plans() if p.get("kind") == "plan"]
        with ctx.outputs(fast=False) as out:
            run_ = ctx.pm.get("demo", name).factory(
                ctx.profile,
                ctx.pm,
                out,
                camera=cam,
                script=False,
                vision=rec.tunables,
                sinks=[sink],
                tuio=False,
                watchdog_ms=1e9,  # a replay on a busy machine is slow, not unsafe
                prepare_first=True,
            )
            cam.ready = lambda: len(run_.loop.queue) == 0
            try:
                while not (cam.finished and len(run_.loop.queue) == 0):
                    time.sleep(0.05)
                time.sleep(0.3)  # the last frame through its stages
                t_end = time.monotonic() + 10.0
                while len(sink.plans) < len(recorded_plans) and time.monotonic() < t_end:
                    time.sleep(0.05)  # a plan computed off the frame loop still coming
            finally:
                run_.stop()
        if sink.first_diff is None and sink.frames != rec.n_frames:
            sink.first_diff = f"frames: {rec.n_frames} recorded vs {sink.frames} replayed"
        if sink.first_diff is not None:
            return False, f"replay: first difference at {sink.first_diff}" + _versions_note(rec)
        diff = first_plan_difference(recorded_plans, sink.plans)
        if diff is not None:
            return False, f"replay: first difference at {diff}" + _versions_note(rec)
        n_g, _ = _events([rec.decisions(k) for k in range(rec.n_frames)])
        dropped = rec.stats["dropped"]
        were = "was" if dropped == 1 else "were"
        tail = f"; {counted(dropped, 'frame')} {were} dropped while recording" if dropped else ""
        return True, (
            f"replay: {sink.frames} frames, {n_g} gestures and {len(sink.plans)} plans the "
            f"same ({name} demo); {gate_events_text(rec.gate_events())} recorded{tail}"
        )
