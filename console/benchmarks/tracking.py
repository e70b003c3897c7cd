"""``haptable bench tracking``: identities of a resting hand and its fingertips on the twin.

The camera twin shows a resting open hand for 10 s (600 frames at 60 fps; ``--quick``:
2 s), then the hand lifts and comes back with two fingers down for 5 s (1 s). Each frame
goes through the profile's classifier (vision) and ``console.runtime.tracking.Tracking``.
Reported: the tracker's own time per frame (p50/p99/max), the vision's for scale, blob
(hand) sessions per 10 s of the resting hand, contact sessions of the two fingers, and
the frame-to-frame step of the tracked hand centre against the palm centre's (mm).
"""

from __future__ import annotations

import time
from typing import Any

import numpy as np

from console.core.bench_stats import machine_info, summarize_s
from console.core.contracts import SimulatedCamera
from console.core.errors import UserError
from console.core.types import GestureScript, GestureStep
from console.runtime.stages import learn_background, open_classifier
from console.runtime.tracking import Tracking


def _steps_mm(points: list[tuple[int, np.ndarray]]) -> dict[str, float]:
    """p50/p99/max of the distance between consecutive positions of the same id."""
    steps = [
        float(np.hypot(*(b - a)))
        for (ia, a), (ib, b) in zip(points, points[1:], strict=False)
        if ia == ib
    ]
    if not steps:
        return {"n": 0, "p50_mm": float("nan"), "p99_mm": float("nan"), "max_mm": float("nan")}
    s = np.asarray(steps)
    return {
        "n": int(s.size),
        "p50_mm": float(np.percentile(s, 50)),
        "p99_mm": float(np.percentile(s, 99)),
        "max_mm": float(s.max()),
    }


def run(ctx: Any, quick: bool) -> dict[str, Any]:
    profile, pm = ctx.profile, ctx.pm
    fps = float(profile.get("camera.fps", 60.0))
    n_rest, n_two, gap = (
        (int(2 * fps), int(fps), 30) if quick else (int(10 * fps), int(5 * fps), 30)
    )
    camera = pm.build("camera", "twin", profile)
    if not isinstance(camera, SimulatedCamera):
        camera.close()
        raise UserError("bench tracking: the camera twin plugin is needed (camera 'twin')")
    camera.realtime = False
    script = GestureScript(
        (GestureStep("open_hand", frames=n_rest), GestureStep("two_finger", frames=n_two)),
        gap_frames=gap,
        loop=False,
    )
    try:
        camera.set_script(script)
        clf = open_classifier(profile, pm)
        learn_background(camera, clf)
        tracking = Tracking(clf.to_mm)
        t_track: list[float] = []
        t_vision: list[float] = []
        rest: list[tuple[int, np.ndarray]] = []
        palm: list[tuple[int, np.ndarray]] = []
        rest_ids: set[int] = set()
        contact_ids: set[int] = set()
        for k in range(gap + n_rest + gap + n_two):
            frame = camera.read(1.0)
            t0 = time.perf_counter()
            res = clf.process(frame)
            t1 = time.perf_counter()
            tf = tracking.update(frame.t_capture_s, tuple(res.hands), tuple(res.contacts))
            t_track.append(time.perf_counter() - t1)
            t_vision.append(t1 - t0)
            resting = gap <= k < gap + n_rest
            for h, tr in zip(tf.hands, tf.hand_tracks, strict=True):
                if resting:
                    rest_ids.add(tr.id)
                    rest.append((tr.id, tr.pos.copy()))
                    if h.center_mm is not None:
                        palm.append((0, np.asarray(h.center_mm, float)))
            if k >= 2 * gap + n_rest:
                contact_ids.update(t.id for t in tf.contact_tracks)
    finally:
        camera.close()
    return {
        "frames": len(t_track),
        "tracker": summarize_s(t_track),
        "vision": summarize_s(t_vision),
        "resting_hand": {
            "seconds": n_rest / fps,
            "blob_sessions": len(rest_ids),
            "blob_sessions_per_10s": len(rest_ids) * 10.0 * fps / n_rest,
            "tracked_centre_step": _steps_mm(rest),
            "palm_centre_step": _steps_mm(palm),
        },
        "two_fingers": {"seconds": n_two / fps, "contact_sessions": len(contact_ids)},
        "machine": machine_info(),
    }
