"""What only a gesture decision reads (a hand's Fourier descriptors and finger count, the
hands' touching skin) is made on first read: a frame loop that does not decide on a
frame does not pay for it, and whoever reads it gets what the eager pipeline gave."""

import dataclasses
import pickle

import numpy as np

from plugins.gestures import sketch
from plugins.gestures.descriptors import fourier_descriptors
from plugins.gestures.features import frame_record
from plugins.gestures.vision import VisionParams, process_frame

BG = sketch.background()
P = VisionParams()


def two_finger_frame():
    pose = sketch.HandPose((320, 240), -90.0, "two_finger", flat=False)
    return sketch.draw([pose], BG, noise=2.0, rng=np.random.default_rng(0))


def test_the_loop_s_frames_leave_shape_and_touch_unmade_until_read():
    res = process_frame(two_finger_frame(), BG, P)
    hand = res.hands[0]
    assert not hand.shape.known and res.touch._regions is None
    # the tracker's per-frame copy keeps it unmade
    moved = dataclasses.replace(hand, contacts=hand.contacts[:1])
    assert not moved.shape.known
    rec = frame_record(res)
    assert hand.shape.known and moved.shape.known and res.touch._regions is not None
    assert rec["fingers"] == 2 == moved.finger_count
    square = np.array([[0, 0], [9, 0], [9, 9], [0, 9]], float)
    assert len(rec["descriptors"]) == len(fourier_descriptors(square, P.n_harmonics))


def test_touching_skin_read_later_is_at_the_fingertips():
    pose = sketch.HandPose((320, 240), -90.0, "two_finger", flat=False)
    res = process_frame(two_finger_frame(), BG, P)
    two = process_frame(two_finger_frame(), BG, P)  # the frame after: not read yet
    regions = res.touch.of(0)["regions"]
    assert len(regions) == 2 and two.touch._regions is None
    for tip in sketch.fingertips_px(pose):
        assert np.min(np.hypot(*(regions[:, 1:] - tip).T)) < 6.0


def test_a_hand_pickles_with_its_values_not_a_recipe():
    hand = process_frame(two_finger_frame(), BG, P).hands[0]
    back = pickle.loads(pickle.dumps(hand))
    assert back.shape.known and back.finger_count == hand.finger_count == 2
    np.testing.assert_array_equal(back.descriptors, hand.descriptors)
