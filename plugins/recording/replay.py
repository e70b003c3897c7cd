"""Replay a recording through the vision and gesture stages a demo runs, and compare.

``replay(path, profile, plugins)`` (``--vision-only``) builds the stages the
demo runner builds (``vision``, ``classify`` with ``[demos] still_mm/still_ms``), starts
them from the recording's learned background and tunables, runs every frame through
``FrameLoop.process`` (no frame dropped) and compares each frame's contacts, hands,
gesture, named gesture and resting place with the recorded ones as JSON text (bit for bit).
Plans are counted, not re-planned (the flow demo's plan depends on the outputs' timing).
"""

from __future__ import annotations

from pathlib import Path
from typing import Any

from console.plugin_api import UserError, counted, gate_events_text
from console.plugin_api.runtime import FrameLoop, VisionStage, open_classifier

from .camera import ReplayCamera
from .decisions import compare, frame_decisions
from .reader import Recording, open_recording


def _events(decs: list[dict]) -> tuple[int, int]:
    """(gestures, plans): gesture onsets (a frame whose gesture differs from the frame
    before and is not none, or a named gesture) and plans decided on a frame."""
    n_g, prev = 0, None
    n_p = 0
    for d in decs:
        g = d.get("gesture")
        name = g[0] if g else None
        if (name is not None and name != prev) or d.get("named"):
            n_g += 1
        prev = name
        n_p += "plan" in d
    return n_g, n_p


def replay(path: str | Path, profile: Any, plugins: Any) -> tuple[bool, str]:
    """(same, one line): every frame's decisions the same, or the first difference."""
    with open_recording(path) as rec:
        if rec.n_frames == 0:
            raise UserError(f"recording {rec.path}: no frame was recorded; record a longer run")
        clf = open_classifier(profile, plugins)
        bg = rec.background()
        if bg is not None:
            clf.set_background(bg)
        for key, value in rec.tunables.items():
            clf.set_tunable(key, value)
        dm = profile.section("demos")
        gestures = clf.gesture_stage(
            still_mm=float(dm.get("still_mm", 12.0)), still_s=float(dm.get("still_ms", 300)) / 1e3
        )
        camera = ReplayCamera(rec)
        loop = FrameLoop(camera, [("vision", VisionStage(clf)), ("classify", gestures)])
        recorded = []
        k = 0
        while (frame := camera.read()) is not None:
            work = loop.process(frame)
            if loop.last_error:
                return False, f"replay: frame {frame.seq} failed: {loop.last_error}"
            want = rec.decisions(k)
            recorded.append(want)
            diff = compare(frame.seq, want, frame_decisions(work))
            if diff is not None:
                return False, f"replay: first difference at {diff}" + _versions_note(rec)
            k += 1
        n_g, _ = _events(recorded)
        n_p = sum(p.get("kind") == "plan" for p in rec.plans())
        dropped = rec.stats["dropped"]
        were = "was" if dropped == 1 else "were"
        tail = f"; {counted(dropped, 'frame')} {were} dropped while recording" if dropped else ""
        return True, (
            f"replay: {counted(rec.n_frames, 'frame')}, {n_g} gestures the same; {n_p} plans "
            f"recorded (not re-planned), {gate_events_text(rec.gate_events())}{tail}"
        )


def _versions_note(rec: Recording) -> str:
    """Why a replay may differ: frames the recorder dropped, other versions."""
    from .writer import versions  # lazy: imports cv2 and h5py

    now, then = versions(), rec.versions
    diff = [f"{k} {then.get(k)} -> {now[k]}" for k in now if then.get(k) != now[k]]
    note = f" (versions differ: {', '.join(diff)})" if diff else " (same versions)"
    if len(rec.dropped_seq):
        note += (
            f"; the recorder dropped {counted(len(rec.dropped_seq), 'frame')}, the first {rec.dropped_seq[0]}"
            ": the run saw them, the replay cannot"
        )
    return note
