"""The live gesture rules (plugins/gestures/rules.py): a resting hand once per placement,
the two-finger grip, the model's decision once per placement from the vision results
the loop already has."""

from __future__ import annotations

from collections import deque
from types import SimpleNamespace

import numpy as np
import pytest

from console.core.types import Contact, Frame, Gesture, Hand, HandShape
from plugins.gestures.classifier import SvmClassifier
from plugins.gestures.rules import GestureRules, PalmWindow, StillHand


def test_still_hand_fires_once_per_placement():
    s = StillHand(still_mm=5, still_s=0.3, lift_s=0.2, moved_mm=40)
    fired = [s.update(t, (100.0, 100.0)) for t in np.arange(0, 1.0, 1 / 60)]
    hits = [i for i, f in enumerate(fired) if f is not None]
    assert len(hits) == 1
    assert hits[0] == 18  # 0.3 s at 60 fps
    assert fired[hits[0]] == pytest.approx((100.0, 100.0))


def test_still_hand_waits_while_moving_and_rearms_after_a_lift_or_a_move():
    s = StillHand(still_mm=5, still_s=0.2, lift_s=0.1, moved_mm=40)
    t = 0.0
    for k in range(30):  # sliding 2 mm per frame: never still
        assert s.update(t, (100.0 + 2 * k, 50.0)) is None
        t += 1 / 60
    got = None
    for _ in range(20):
        got = got or s.update(t, (160.0, 50.0))
        t += 1 / 60
    assert got == pytest.approx((160.0, 50.0))
    for _ in range(3):  # a short gap (under lift_s) does not re-arm
        s.update(t, None)
        t += 1 / 60
    assert all(s.update(t + i / 60, (160.0, 50.0)) is None for i in range(20))
    t += 20 / 60
    for _ in range(10):  # lifted
        s.update(t, None)
        t += 1 / 60
    again = [s.update(t + i / 60, (160.0, 50.0)) for i in range(20)]
    assert sum(a is not None for a in again) == 1
    t += 20 / 60
    moved = [s.update(t + i / 60, (260.0, 50.0)) for i in range(20)]
    assert sum(m is not None for m in moved) == 1


class FakeModelClassifier:
    """A classifier with a trained model: names a gesture from a window of results."""

    n_frames = 3  # the trained model's window

    def __init__(self) -> None:
        self.calls: list[tuple[list, float]] = []

    def classify(self, window, t_s):
        self.calls.append((list(window), t_s))
        return Gesture("l_shape", "static", 0.8, t_s, None)


def _hand(center_mm, n_contacts=0):
    cs = tuple(Contact(i, (0.0, 0.0), (0.0, 0.0)) for i in range(n_contacts))
    return Hand(
        np.zeros((3, 2)),
        (0.0, 0.0),
        10.0,
        0.0,
        HandShape.of(np.zeros(3), n_contacts),
        cs,
        center_mm,
    )


def test_gesture_rules_name_a_placement_once_and_report_rest_and_grip():
    clf = FakeModelClassifier()
    st = GestureRules(clf, StillHand(still_mm=5, still_s=0.1))
    names, results = [], []
    for k in range(20):
        f = Frame(np.zeros((2, 2), np.uint8), k, k / 60)
        hand = _hand((200.0, 100.0), 2 if k >= 12 else 0)
        results.append(SimpleNamespace(hands=(hand,), contacts=hand.contacts))
        work = {"hand": hand, "result": results[-1]}
        st(f, work)
        names.append((work["gesture"].name if work["gesture"] else None, work.get("rest_mm")))
        assert ("named" in work) == (k == 2)
    # once per placement, from the vision results the loop gave it, at the frame's time
    assert len(clf.calls) == 1
    window, t_s = clf.calls[0]
    assert all(a is b for a, b in zip(window, results[:3], strict=True)) and t_s == 2 / 60
    assert names[2][0] == "l_shape"
    rest = [i for i, (_, r) in enumerate(names) if r is not None]
    assert rest == [6] and names[6][0] == "static_hand"
    assert all(n == "two_finger" for n, _ in names[12:])
    st(Frame(np.zeros((2, 2), np.uint8), 20, 1.0), {"hand": None, "result": None})
    assert st.window.maxlen and len(st.window) == 0
    for k in range(21, 24):  # the next placement is named again, from its own results
        st(
            Frame(np.zeros((2, 2), np.uint8), k, k / 60),
            {"hand": _hand((90.0, 60.0))} | {"result": results[k - 21]},
        )
    assert len(clf.calls) == 2 and clf.calls[1][1] == 23 / 60


@pytest.mark.parametrize("n_frames", [0, 3])
def test_no_vision_result_is_kept_past_the_decision_nor_without_a_model(n_frames):
    # each result holds its frame's images: the loop's memory (and the frames that free
    # them) should not hold six frames a placement for nothing
    clf = FakeModelClassifier()
    clf.n_frames = n_frames
    st = GestureRules(clf)
    kept = []
    for k in range(12):
        hand = _hand((200.0, 100.0))
        st(Frame(np.zeros((2, 2), np.uint8), k, k / 60), {"hand": hand, "result": object()})
        kept.append(len(st.window))
    assert kept == ([0] * 12 if n_frames == 0 else [1, 2, 3] + [3] * 9)
    assert len(clf.calls) == (n_frames > 0)


def test_the_svm_classifier_decides_from_results_without_processing_again():
    """``classify(window, t_s)`` takes ``process``'s results: no frame goes through the
    vision again, none is stamped again; no model or no hand: ``None``."""
    from plugins.twin.camera.camera import TwinCamera

    cam = TwinCamera(realtime=False, seed=1)
    clf = SvmClassifier(None)
    clf.set_background(cam.background())
    cam.place("open_hand", (370.0, 220.0))
    frames = [cam.read() for _ in range(3)]
    results = [clf.process(f) for f in frames]
    stamps = [f.stamps_s["vision"] for f in frames]
    assert clf.classify(results, frames[-1].t_capture_s) is None  # no model
    clf.model = SimpleNamespace(
        n_frames=3,
        n_harmonics=4,
        predict=lambda *a: np.array(["open_hand"]),
        confidence=lambda *a: np.array([0.7]),
    )
    clf.process = None  # would fail if called
    g = clf.classify(results, frames[-1].t_capture_s)
    assert g.name == "open_hand" and g.kind == "static" and g.confidence == 0.7
    assert g.t_s == frames[-1].t_capture_s and g.hand is results[-1].hands[0]
    assert [f.stamps_s["vision"] for f in frames] == stamps
    empty = SimpleNamespace(hands=(), contacts=())
    assert clf.classify([empty] * 3, 0.0) is None and clf.classify([], 0.0) is None


def test_the_palm_window_s_mean_is_the_plain_mean_of_its_positions():
    """``settle_mm`` (where a palm rests so far) is the mean of the palm positions since
    the hand came to rest, at most the last 600: the window keeps them in one array (a
    hand resting for minutes does not stack 600 positions again each frame) and gives
    the plain list's ``np.mean`` bit for bit, through drops, clears and its array's end."""
    rng = np.random.default_rng(5)
    win, plain = PalmWindow(600), deque(maxlen=600)
    t0, compared = 0.0, 0
    for k in range(4000):
        t = k / 60
        if k % 1500 == 1499:  # the hand lifts
            win.clear()
            plain.clear()
        if k % 700 == 0:  # it comes to rest again: the window starts there
            t0 = t - rng.uniform(0, 2)
        xy = rng.normal(300.0, 40.0, 2)
        win.append(t, xy)
        plain.append((t, xy))
        while plain and plain[0][0] < t0:
            plain.popleft()
        got = win.mean_since(t0)
        assert np.array_equal(got, np.mean([q for _, q in plain], axis=0))
        assert len(win) == len(plain)
        compared += len(plain) == 600
    assert compared > 300  # the window was full (and its array's end passed) many times
