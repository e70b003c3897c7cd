"""The frame loop's cheaper paths give the plain paths' results (issue 28's cost): on the
camera twin, the loop's decisions (contacts, hands, gestures, where a palm rests) and the
classifier's features for every frame are bit for bit those of a loop with the plain
implementations (the body's parts from their definition, the background blended under a
frame-sized mask, the resting palm averaged over a list, the outline's centroid with
``np.roll``) that also computes every frame's features at once, the old eager way. What
only a decision reads (a hand's shape, the touching skin) is computed on the decision's
frames only."""

from __future__ import annotations

import json
from collections import deque
from dataclasses import replace

import numpy as np
import pytest

import console.runtime.tracking as tracking
import plugins.gestures.rules as rules
import plugins.gestures.touch as touch
import plugins.gestures.vision as vision
from console.core.types import GestureScript, GestureStep
from console.runtime.loop import FrameLoop
from console.runtime.stages import base_stages, learn_background, open_camera, open_classifier
from plugins.gestures.background import Background
from plugins.gestures.features import frame_record
from plugins.recording.decisions import frame_decisions

from .plain_vision import plain_body_parts
from .test_frame_seen_once import NamingModel

#: a resting pose, a slide and a two-finger grip, an empty table before each
STEPS = (
    GestureStep("open_hand", "s1", None, 14),
    GestureStep("drag", "s2", None, 14),
    GestureStep("two_finger", "s1", None, 14),
)
N_FRAMES = 66


class PlainPalms:
    """``rules.PalmWindow`` as a list of positions averaged with ``np.mean``."""

    def __init__(self, size: int) -> None:
        self._q: deque = deque(maxlen=size)

    def __len__(self) -> int:
        return len(self._q)

    def clear(self) -> None:
        self._q.clear()

    def append(self, t_s, xy) -> None:
        self._q.append((t_s, np.asarray(xy, float)))

    def mean_since(self, t0_s):
        while self._q and self._q[0][0] < t0_s:
            self._q.popleft()
        return np.mean([q for _, q in self._q], axis=0)


def plain_centroid(contour_px):
    c = np.asarray(contour_px, float).reshape(-1, 2)
    if len(c) < 3:
        return None
    x, y = c[:, 0], c[:, 1]
    xn, yn = np.roll(x, -1), np.roll(y, -1)
    cross = x * yn - xn * y
    a = cross.sum() / 2.0
    if abs(a) < 1e-9:
        return None
    return float(((x + xn) * cross).sum() / (6 * a)), float(((y + yn) * cross).sum() / (6 * a))


def _plain(monkeypatch) -> None:
    monkeypatch.setattr(vision, "body_parts", plain_body_parts)
    monkeypatch.setattr(rules, "PalmWindow", PlainPalms)
    monkeypatch.setattr(tracking, "outline_centroid", plain_centroid)
    update = Background.update

    def frame_sized(self, frame, foreground=None, gain=1.0, offset=0.0, window=None):
        full = np.zeros(frame.shape, np.uint8)  # without a hand: nothing is foreground
        if foreground is not None:
            x0, y0, x1, y1 = window or (0, 0, frame.shape[1], frame.shape[0])
            full[y0:y1, x0:x1] = foreground
        update(self, frame, full, gain, offset)

    monkeypatch.setattr(Background, "update", frame_sized)


def _run(profile, plugins, *, plain: bool, counted: dict | None = None):
    """Per frame: its decisions as the recorder writes them, its features and whether
    the model decided on it; the background at the end; per frame, whether what only a
    decision reads was made before a decision read it, and (``counted``) how many were
    made while the loop ran."""
    cam = open_camera(profile, plugins)
    cam.realtime = False
    cam.set_script(GestureScript(STEPS, gap_frames=8, loop=False, seed=4))
    early = []
    try:
        clf = open_classifier(profile, plugins)
        learn_background(cam, clf)
        clf.model = NamingModel()
        loop = FrameLoop(cam, base_stages(clf))
        works, records = [], []
        for _ in range(N_FRAMES):
            # the frame's time at the camera's rate, not the wall clock's (the camera's
            # when not real time): a slow run, the plain one on a loaded machine, sees
            # the hand rest as long as a fast one does
            frame = cam.read()
            work = loop.process(replace(frame, t_capture_s=frame.seq / cam.fps))
            res = work["result"]
            if not plain:
                early.append(
                    "named" not in work
                    and (any(h.shape.known for h in res.hands) or _touch_made(res))
                )
            works.append(work)
            records.append(frame_record(res) if plain else None)  # eager: at once
        background = clf.background.image.copy()
    finally:
        cam.close()
    assert loop.monitor.snapshot()["errors"] == 0
    made_in_loop = dict(counted or {})
    if not plain:  # read now, long after the loop made the frames
        records = [frame_record(w["result"]) for w in works]
    decisions = [json.dumps(frame_decisions(w)) for w in works]
    named = ["named" in w for w in works]
    return decisions, records, named, background, early, made_in_loop


def _touch_made(res) -> bool:
    return res.touch is not None and res.touch._regions is not None


@pytest.fixture
def counted(monkeypatch):
    """Counts the hands' shapes and the frames' touching skin as they are made."""
    made = {"shape": 0, "touch": 0}
    shape, regions = vision.hand_shape, touch.touch_regions

    def hand_shape(*a, **kw):
        made["shape"] += 1
        return shape(*a, **kw)

    def touch_regions(*a, **kw):
        made["touch"] += 1
        return regions(*a, **kw)

    monkeypatch.setattr(vision, "hand_shape", hand_shape)
    monkeypatch.setattr(touch, "touch_regions", touch_regions)
    return made


def test_the_loop_gives_the_plain_eager_loop_s_results_and_decides_from_few_frames(
    profile, plugins, monkeypatch, counted
):
    got = _run(profile, plugins, plain=False, counted=counted)
    with monkeypatch.context() as m:
        _plain(m)
        want = _run(profile, plugins, plain=True)
    decisions, records, named, background, early, made_in_loop = got
    assert decisions == want[0]  # contacts, hands, gestures, resting palm: the same text
    assert named == want[2] and sum(named) == 3  # one decision per placement
    assert sum(r is not None for r in records) > 30
    for a, b in zip(records, want[1], strict=True):
        np.testing.assert_equal(a, b)  # every feature, bit for bit
    np.testing.assert_array_equal(background, want[3])
    # what only a decision reads: made on the decisions' frames (3 per placement, one
    # hand each), never on a frame before it was read
    assert not any(early)
    assert made_in_loop == {"shape": 9, "touch": 9}


def test_the_table_mapping_s_plain_floats_give_the_matrix_product_s_decisions(
    profile, plugins, monkeypatch
):
    # a frame's few points are mapped to mm in Python floats, not through the matrix
    # product (a few units in the last place apart): the loop decides the same (its
    # mm within 1e-9), from the same features bit for bit
    import console.runtime.stages as stages

    got = _run(profile, plugins, plain=True)
    with monkeypatch.context() as m:
        m.setattr(stages, "SMALL_BATCH", 0)  # every batch through the product
        want = _run(profile, plugins, plain=True)
    assert got[0] != want[0]  # the last places of the mm do differ
    for a, b in zip(got[0], want[0], strict=True):  # contacts, hands, gestures, palm
        _assert_close(json.loads(a), json.loads(b))
    assert got[2] == want[2] and sum(got[2]) == 3
    assert sum(r is not None for r in got[1]) > 30
    for a, b in zip(got[1], want[1], strict=True):
        np.testing.assert_equal(a, b)  # every feature, bit for bit
    np.testing.assert_array_equal(got[3], want[3])


def _assert_close(a, b) -> None:
    """The same decisions: names, ids and counts equal, numbers within 1e-9."""
    assert type(a) is type(b)
    if isinstance(a, dict):
        assert a.keys() == b.keys()
        for k in a:
            _assert_close(a[k], b[k])
    elif isinstance(a, list):
        assert len(a) == len(b)
        for x, y in zip(a, b, strict=True):
            _assert_close(x, y)
    elif isinstance(a, float):
        assert a == pytest.approx(b, rel=1e-9, abs=1e-9)
    else:
        assert a == b
