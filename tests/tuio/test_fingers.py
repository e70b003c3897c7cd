"""Which hand, left or right, which finger (``plugins.tuio.fingers``, ``pointers``): on
hands drawn here with known geometry (both sides, decided and undecided), and on the
camera twin's rendered hands, whose renderer knows each contact's finger."""

from __future__ import annotations

import math

import numpy as np
import pytest

from console.core.types import Contact, Hand, HandShape

R = 40.0  # palm radius (mm = px: the identity mapping, +y ahead of the fingers)
PALM = np.array([300.0, 200.0])
FORWARD_UP = 180.0  # the vision's angle_deg whose fingers point to +y


def identity(p):
    return np.asarray(p, float).reshape(-1, 2)


def disc(center, r, n=360):
    a = np.linspace(0, 2 * np.pi, n, endpoint=False)
    return np.column_stack([center[0] + r * np.cos(a), center[1] + r * np.sin(a)])


def union_outline(discs):
    """The outer outline of a union of discs (OpenCV on a 1 px grid)."""
    import cv2

    m = np.zeros((600, 700), np.uint8)
    for (x, y), r in discs:
        cv2.circle(m, (int(x), int(y)), int(r), 255, -1)
    cs, _ = cv2.findContours(m, cv2.RETR_EXTERNAL, cv2.CHAIN_APPROX_NONE)
    return max(cs, key=cv2.contourArea).reshape(-1, 2).astype(float)


def at_angle(theta_deg, dist_r, side="right"):
    """A point ``dist_r`` palm radii from the palm centre, ``theta_deg`` from the fingers'
    direction towards the little finger (a right hand's little finger is at +x)."""
    t = math.radians(theta_deg)
    w = 1.0 if side == "right" else -1.0
    return PALM + dist_r * R * np.array([w * math.sin(t), math.cos(t)])


def right_hand(thumb=True):
    """A palm with the thumb's bump at -x (left of +y seen from above: a right hand)."""
    parts = [(PALM, R), (PALM + (0, 45), 30)]
    if thumb:
        parts.append((PALM + (-50, 0), 16))
    return union_outline(parts)


def mirror(pts):
    return np.column_stack([600.0 - pts[:, 0], pts[:, 1]])


def test_the_thumb_side_decides_the_hand_and_the_arc_names_each_finger():
    from plugins.tuio.fingers import TEMPLATE_DEG, read_hand, type_id

    tips = np.array([at_angle(t, 2.0) for t in TEMPLATE_DEG])  # thumb .. little
    r = read_hand(right_hand(), FORWARD_UP, tips, identity)
    assert (r.side, r.evidence) == ("right", "outline")
    names = r.fingers(r.side)
    assert names == ("thumb", "index", "middle", "ring", "little")
    assert [type_id("right", f) for f in names] == [5, 1, 2, 3, 4]  # the spec's ids
    # the mirror image is a left hand: the same fingers, ids 6 .. 10
    left = read_hand(mirror(right_hand()), FORWARD_UP, mirror(tips), identity)
    assert left.side == "left" and left.fingers("left") == names
    assert [type_id("left", f) for f in names] == [10, 6, 7, 8, 9]
    # shuffled contacts are ordered along the arc, a common turn of the axis is absorbed
    turned = np.array([at_angle(t + 15.0, 2.0) for t in TEMPLATE_DEG])[[3, 0, 4, 1, 2]]
    got = read_hand(right_hand(), FORWARD_UP, turned, identity).fingers("right")
    assert got == ("ring", "thumb", "little", "index", "middle")


def test_an_undecided_hand_or_finger_stays_unknown_never_a_guess():
    from plugins.tuio.fingers import read_hand

    two = np.array([at_angle(-14, 2.0), at_angle(3, 2.0)])
    plain = read_hand(right_hand(thumb=False), FORWARD_UP, two, identity)  # no thumb shows
    assert plain.side is None and plain.fingers(None) == (None, None)
    # no camera -> table mapping: the image might be mirrored, nothing is decided
    assert read_hand(right_hand(), FORWARD_UP, two, None).fingers("right") == (None, None)
    # a contact behind the palm: the vision's axis is wrong, nothing this frame
    behind = np.array([at_angle(-14, 2.0), PALM + (0, -30)])
    r = read_hand(right_hand(), FORWARD_UP, behind, identity)
    assert r.side is None and r.fingers("right") == (None, None)
    # a lone finger: the index where the index points, unknown between fingers
    one = read_hand(right_hand(), FORWARD_UP, [at_angle(-14, 2.2)], identity)
    assert one.fingers(one.side) == ("index",)
    unsure = read_hand(right_hand(), FORWARD_UP, [at_angle(24, 2.2)], identity)
    assert unsure.side == "right" and unsure.fingers("right") == (None,)


def test_a_contact_belongs_to_the_hand_that_holds_it_or_is_near_and_keeps_its_type():
    from console.runtime.tracking import Tracking
    from plugins.tuio.pointers import PointerTypes

    a, b = right_hand(), mirror(right_hand()) + (200.0, 0.0)  # right at x 300, left at 500
    hands = [
        Hand(a, tuple(PALM), 90.0, FORWARD_UP, HandShape.of(np.zeros(4), 0), ()),
        Hand(b, (500.0, 200.0), 90.0, FORWARD_UP, HandShape.of(np.zeros(4), 0), ()),
    ]
    inside = Contact(0, tuple(at_angle(-14, 1.6)))  # on hand a, not in its vision list
    near = Contact(1, (500.0, 285.0))  # 10 px past b's outline (its top: y 275)
    far = Contact(2, (650.0, 500.0))  # on no hand
    tracking, types = Tracking(identity), PointerTypes()
    for k in range(3):
        tr = tracking.update(k / 60, hands, [inside, near, far])
        got = types.update(tr, identity)
    ids = [t.id for t in tr.contact_tracks]
    hand_ids = [t.id for t in tr.hand_tracks]
    assert got[ids[0]].hand_sid == hand_ids[0] and got[ids[0]].type_id == 1  # right index
    assert got[ids[1]].hand_sid == hand_ids[1]
    assert got[ids[2]].hand_sid is None and got[ids[2]].type_id == 0
    assert types.side(hand_ids[0]) == "right" and types.side(hand_ids[1]) == "left"


@pytest.fixture(scope="module")
def twin_scores():
    from console.config.plugins import load_plugins
    from console.config.profile import load_profile
    from console.runtime.stages import open_classifier
    from plugins.tuio.finger_bench import finger_accuracy

    pm = load_plugins()
    prof = load_profile("sim", pm)
    cam = pm.build("camera", "twin", prof)
    try:
        cases = [
            (g, side, subject)
            for g in ("l_shape", "spread_pile", "one_finger")
            for side in ("right", "left")
            for subject in ("s1", "s2")
        ]
        return finger_accuracy(cam, open_classifier(prof, pm), cases, n_frames=2, seed=3)
    finally:
        cam.close()


def test_the_twins_rendered_hands_get_their_fingers_on_both_sides(twin_scores):
    """The renderer's truth is the reference: what is decided is right, and most is."""
    every = twin_scores["all"]
    assert every["pointers"] >= 80
    assert every["correct_of_decided"] == 1.0 and every["sides_correct_of_sided"] == 1.0
    assert every["decided"] >= 0.6
    for side in ("right", "left"):
        case = twin_scores["cases"][f"l_shape/{side}"]  # the thumb and the index flat down
        assert case["hands_sided"] == 1.0 and case["decided"] >= 0.6, (side, case)
        case = twin_scores["cases"][f"spread_pile/{side}"]  # five fingers down
        assert case["decided"] >= 0.5, (side, case)
        lone = twin_scores["cases"][f"one_finger/{side}"]  # pointing: the index
        assert lone["decided"] >= 0.5 and lone["correct_of_decided"] == 1.0, (side, lone)
