"""``haptable bench tuio``: the cost of encoding one frame as TUIO 2.0 (``tuio2``).

Frames from the profile's simulated camera through the vision (an open hand, then two
fingers down) are recorded once, then encoded again and again: ``one_hand`` as seen, and
``four_hands`` (the same hand four times, ids apart: the split path over UDP) timed
per frame. Bytes per bundle, bundles per frame and the outline tolerance reached are
reported beside the times. ``fingers``: pointers' hands and fingers scored on the twin's
rendered hands (``finger_bench``).
"""

from __future__ import annotations

import copy
import dataclasses
import time
from typing import Any

import numpy as np

from console.plugin_api import (
    GestureScript,
    GestureStep,
    machine_info,
    summarize_s,
)
from console.plugin_api import runtime as rt

from .finger_bench import open_twin_camera, run_fingers
from .tuio2 import UDP_LIMIT_BYTES, WS_LIMIT_BYTES, Tuio2Encoder


def record(profile: Any, plugins: Any, n_frames: int) -> list[tuple[Any, Any]]:
    """``(TrackFrame, to_mm)`` of ``n_frames`` twin frames with a hand on the glass."""
    camera = open_twin_camera(profile, plugins)
    try:
        half = n_frames // 2
        camera.set_script(
            GestureScript(
                (GestureStep("open_hand", frames=half), GestureStep("two_finger", frames=half)),
                gap_frames=2,
                loop=True,
            )
        )
        clf = rt.open_classifier(profile, plugins)
        rt.learn_background(camera, clf)
        stage = rt.VisionStage(clf)
        out = []
        for _ in range(4 * n_frames):  # a hand is on the glass in most of them
            if len(out) == n_frames:
                break
            work: dict = {}
            stage(camera.read(1.0), work)
            if work["tracks"].hands:
                out.append((work["tracks"], work["to_mm"]))
        return out
    finally:
        camera.close()


def four_hands(tracks: Any) -> Any:
    """The frame's first hand four times over, each its own track id."""
    h, tr = tracks.hands[0], tracks.hand_tracks[0]
    trs = []
    for k in range(4):
        t = copy.copy(tr)
        t.id = 10_000 + k
        trs.append(t)
    return dataclasses.replace(
        tracks,
        hands=(h,) * 4,
        hand_tracks=tuple(trs),
        live_hands=tuple(trs),
        contacts=(),
        contact_tracks=(),
        live_contacts=(),
    )


def _case(frames: list, profile: Any, limit_bytes: int, repeats: int) -> dict:
    table = (float(profile.get("table.width_mm")), float(profile.get("table.height_mm")))
    enc = Tuio2Encoder(table_mm=table, limit_bytes=limit_bytes)
    times, sizes, counts, eps = [], [], [], []
    for _ in range(repeats):
        for tracks, to_mm in frames:
            t0 = time.perf_counter()
            out = enc.bundles(tracks, to_mm)
            times.append(time.perf_counter() - t0)
            sizes += [len(b) for b in out]
            counts.append(len(out))
            eps.append(enc.eps_px)
    return {
        "encode": summarize_s(times),
        "bundle_bytes_p50": float(np.median(sizes)),
        "bundle_bytes_max": int(max(sizes)),
        "limit_bytes": limit_bytes,
        "bundles_per_frame_max": int(max(counts)),
        "outline_eps_px_max": float(max(eps)),
        "contours_dropped": enc.contours_dropped,
    }


def run_bench(ctx: Any, quick: bool) -> dict:
    frames = record(ctx.profile, ctx.pm, 40 if quick else 200)
    many = [(four_hands(t), m) for t, m in frames]
    reps = 2 if quick else 5
    return {
        "frames": len(frames),
        "one_hand_udp": _case(frames, ctx.profile, UDP_LIMIT_BYTES, reps),
        "four_hands_udp": _case(many, ctx.profile, UDP_LIMIT_BYTES, reps),
        "four_hands_websocket": _case(many, ctx.profile, WS_LIMIT_BYTES, reps),
        "fingers": run_fingers(ctx.profile, ctx.pm, quick),
        "machine": machine_info(),
    }
