"""Which hand and which finger, scored on the camera twin's rendered hands (the renderer
knows each contact's finger and each hand's side): ``haptable bench tuio`` rows
``fingers`` (``finger_accuracy``), shared with the tests.

Each case (gesture, side, subject) is one short performance rendered offline
(``SimulatedCamera.render_sample``), each frame through the vision and tracking, then
``pointers.PointerTypes`` (the encoder's own path). A vision contact is scored against
the rendered contact within ``MATCH_PX``; the others (none rendered there) are left out.
"""

from __future__ import annotations

import time
from collections import Counter
from typing import Any

import numpy as np

from console.plugin_api import Frame, SimulatedCamera, UserError, summarize_s
from console.plugin_api import runtime as rt

from .fingers import type_id
from .pointers import PointerTypes

MATCH_PX = 8.0
#: poses with touching fingers (static and moving), both hands, in the bench
GESTURES = ("one_finger", "two_finger", "l_shape", "drag", "rotate", "spread_pile", "zoom")


def _truth_types(truth_frame: dict) -> list[tuple[np.ndarray, int]]:
    return [
        (np.asarray(c["pos_px"], float), type_id(h["side"], c["finger"]))
        for h in truth_frame["hands"]
        for c in h["contacts"]
    ]


def finger_accuracy(
    camera: Any,
    clf: Any,
    cases: list[tuple[str, str, str]],
    *,
    n_frames: int = 3,
    seed: int = 0,
) -> dict:
    """Pointers decided (type id not 0) and right, per case ``(gesture, side, subject)``
    and in all: ``pointers`` scored, ``decided`` share, ``correct`` share of the decided,
    ``hands_sided``/``sides_correct`` likewise per hand and frame, ``read`` the time per
    frame's ``PointerTypes.update``."""
    rng = np.random.default_rng(seed)
    tally: Counter = Counter()
    per_case: dict[str, Counter] = {}
    times: list[float] = []
    for gesture, side, subject in cases:
        frames, truth = camera.render_sample(
            gesture, subject, 0, rng, n_frames=n_frames, t0_s=10.0, side=side
        )
        clf.set_background(camera.render_background(10.0, rng))
        tracking, types = rt.Tracking(clf.to_mm), PointerTypes()
        case = per_case.setdefault(f"{gesture}/{side}", Counter())
        for k, image in enumerate(frames):
            t_s = 10.0 + k / 60.0
            res = clf.process(Frame(image, k, t_s))
            tracks = tracking.update(t_s, tuple(res.hands), tuple(res.contacts))
            t0 = time.perf_counter()
            got = types.update(tracks, clf.to_mm if tracks.in_mm else None)
            times.append(time.perf_counter() - t0)
            want = _truth_types(truth["frames"][k])
            for tr in tracks.hand_tracks:
                s = types.side(tr.id)
                case["hands"] += 1
                case["hands_sided"] += s is not None
                case["sides_correct"] += s == side
            for c, tr in zip(tracks.contacts, tracks.contact_tracks, strict=True):
                d = [(float(np.hypot(*(p - c.pos_px))), t) for p, t in want]
                if not d or min(d)[0] > MATCH_PX:
                    continue
                ref, kind = min(d)[1], got[tr.id].type_id
                case["pointers"] += 1
                case["decided"] += kind != 0
                case["correct"] += kind != 0 and kind == ref
        tally.update(case)
    return {
        "all": _shares(tally),
        "cases": {name: _shares(c) for name, c in per_case.items()},
        "read": summarize_s(times),
    }


def _shares(c: Counter) -> dict:
    n, h = c["pointers"], c["hands"]
    return {
        "pointers": n,
        "decided": round(c["decided"] / n, 3) if n else None,
        "correct_of_decided": round(c["correct"] / c["decided"], 3) if c["decided"] else None,
        "hands": h,
        "hands_sided": round(c["hands_sided"] / h, 3) if h else None,
        "sides_correct_of_sided": round(c["sides_correct"] / c["hands_sided"], 3)
        if c["hands_sided"]
        else None,
    }


def open_twin_camera(profile: Any, plugins: Any) -> Any:
    """The profile's camera for ``bench tuio``, which needs the twin's (closed and
    refused in one line otherwise)."""
    camera = rt.open_camera(profile, plugins)
    if not isinstance(camera, SimulatedCamera):
        camera.close()
        raise UserError(
            "bench tuio: the profile's camera is not simulated; run it with the twin "
            "(--profile sim)"
        )
    return camera


def run_fingers(profile: Any, plugins: Any, quick: bool) -> dict:
    """The ``fingers`` rows of ``haptable bench tuio``: every gesture of ``GESTURES``,
    both hands, 2 subjects (quick) or 5."""
    camera = open_twin_camera(profile, plugins)
    try:
        clf = rt.open_classifier(profile, plugins)
        subjects = ("s1", "s2") if quick else ("s1", "s2", "s3", "s4", "s5")
        cases = [(g, side, s) for g in GESTURES for side in ("right", "left") for s in subjects]
        return finger_accuracy(camera, clf, cases, n_frames=3 if quick else 6, seed=7)
    finally:
        camera.close()
