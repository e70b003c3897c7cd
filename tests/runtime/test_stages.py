"""Shared stages: resting-hand detection, camera -> table mapping, vision on the twin."""

from __future__ import annotations

import numpy as np
import pytest

from console.runtime.stages import (
    StillHand,
    VisionStage,
    corners_homography,
    fallback_to_mm,
    learn_background,
    open_camera,
    open_classifier,
)


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


def test_corners_homography_maps_the_corners_exactly():
    corners = [600.0, 20.0, 40.0, 30.0, 50.0, 450.0, 590.0, 440.0]
    to_mm = corners_homography(corners, (700.0, 400.0))
    px = np.array(corners).reshape(4, 2)
    mm = to_mm(px)
    assert mm == pytest.approx(np.array([[0, 0], [700, 0], [700, 400], [0, 400]]), abs=1e-6)


@pytest.fixture
def twin(profile, plugins):
    cam = open_camera(profile, plugins)
    cam.realtime = False
    yield cam
    cam.close()


def test_twin_contacts_land_where_the_ground_truth_says(profile, plugins, twin):
    from plugins.twin.camera import SequenceScript

    twin.set_script(
        SequenceScript(
            [("two_finger", "s1", None, 40)],
            table_mm=(743.46, 447.29),
            gap_frames=0,
            loop=True,
            seed=3,
        )
    )
    clf = open_classifier(profile, plugins)
    learn_background(twin, clf)
    stage = VisionStage(clf)
    errs = []
    for _ in range(6):
        f = twin.read()
        work: dict = {}
        stage(f, work)
        truth = np.array(twin.truth["contacts_mm"])
        for c in work["contacts"]:
            assert c.pos_mm is not None
            errs.append(np.hypot(*(truth - c.pos_mm).T).min())
        assert work["hand"] is not None and work["hand"].center_mm is not None
    assert len(errs) >= 6
    assert np.median(errs) < 6.0  # mm: a fingertip is ~15 mm wide


def test_no_fallback_mapping_off_the_twin(profile):
    class P:
        def get(self, key, default=None):
            return {"camera.driver": "opencv"}.get(key, profile.get(key, default))

    assert fallback_to_mm(P()) is None
    assert fallback_to_mm(profile) is not None


class FakeModelClassifier:
    """A classifier with a trained model: names a gesture from a window of frames."""

    n_frames = 3  # the trained model's window

    def __init__(self) -> None:
        self.calls: list[int] = []

    def classify(self, frames):
        from console.types import Gesture

        self.calls.append(len(frames))
        return Gesture("l_shape", "static", 0.8, frames[-1].t_capture_s, None)


def _hand(center_mm, n_contacts=0):
    from console.types import Contact, Hand

    cs = tuple(Contact(i, (0.0, 0.0), (0.0, 0.0)) for i in range(n_contacts))
    return Hand(np.zeros((3, 2)), (0.0, 0.0), 10.0, 0.0, np.zeros(3), n_contacts, cs, center_mm)


def test_gesture_stage_names_a_placement_once_and_reports_rest_and_grip():
    from console.runtime.stages import GestureStage
    from console.types import Frame

    clf = FakeModelClassifier()
    st = GestureStage(clf, StillHand(still_mm=5, still_s=0.1))
    names = []
    for k in range(20):
        f = Frame(np.zeros((2, 2), np.uint8), k, k / 60)
        work = {"hand": _hand((200.0, 100.0), 2 if k >= 12 else 0)}
        st(f, work)
        names.append((work["gesture"].name if work["gesture"] else None, work.get("rest_mm")))
    assert clf.calls == [3]  # once per placement, from the model's window
    assert names[2][0] == "l_shape"
    rest = [i for i, (_, r) in enumerate(names) if r is not None]
    assert rest == [6] and names[6][0] == "static_hand"
    assert all(n == "two_finger" for n, _ in names[12:])
    st(Frame(np.zeros((2, 2), np.uint8), 20, 1.0), {"hand": None})
    assert st.window.maxlen and len(st.window) == 0
