"""Gesture features: similarity fit, contact tracks, motion of sketched gestures."""

import math

import numpy as np
import pytest

from plugins.gestures import sketch
from plugins.gestures.features import (
    contact_tracks,
    dynamic_features,
    frame_record,
    motion_features,
    motion_score,
    similarity,
    static_features,
    static_size,
)
from plugins.gestures.vision import VisionParams, process_frame

BG = sketch.background()
P = VisionParams()


def records(gesture, n=4, **kw):
    poses = sketch.gesture_poses(gesture, n, **kw)
    return [
        frame_record(process_frame(sketch.draw([h], BG, rng=np.random.default_rng(i)), BG, P))
        for i, h in enumerate(poses)
    ]


def test_similarity_recovers_a_known_transform():
    rng = np.random.default_rng(0)
    a = rng.uniform(-50, 50, (5, 2))
    ang, s, t = math.radians(25), 1.3, np.array([4.0, -7.0])
    rot = np.array([[math.cos(ang), -math.sin(ang)], [math.sin(ang), math.cos(ang)]])
    b = s * a @ rot.T + t
    tt, r, ls = similarity(a, b)
    assert r == pytest.approx(ang, abs=1e-9)
    assert ls == pytest.approx(math.log(s), abs=1e-9)
    # translation reported is of the centroids
    np.testing.assert_allclose(tt, b.mean(0) - a.mean(0), atol=1e-9)
    # one point or coincident points: translation only, no NaN
    assert similarity(a[:1], b[:1])[1:] == (0.0, 0.0)
    assert similarity(np.zeros((3, 2)), np.ones((3, 2)))[1:] == (0.0, 0.0)


def test_tracks_follow_contacts_and_drop_vanishing_ones():
    def rec(pts):
        return {"contacts_px": np.array(pts, float).reshape(-1, 2)}

    recs = [rec([[0, 0], [100, 0]]), rec([[102, 1], [3, 0]]), rec([[6, 0]])]
    tracks = contact_tracks(recs, gate_px=20)
    assert len(tracks) == 1
    np.testing.assert_allclose(tracks[0][:, 0], [0, 3, 6])
    assert contact_tracks([rec([[0, 0]]), None], 20) == []


def test_static_pose_has_no_motion_and_dynamic_ones_do():
    still = motion_score(records("two_finger"))
    assert still < 0.05
    for g in sketch.DYNAMIC:
        assert motion_score(records(g)) > 5 * max(still, 0.01), g


def test_rotate_turns_about_a_pivot_and_zoom_scales():
    rot = motion_features(records("rotate", 4))
    zoom = motion_features(records("zoom", 4))
    drag = motion_features(records("drag", 4))
    # rotate: contacts turn (index 13, in units of 20 deg) and one barely moves (pivot)
    assert rot[13] > 0.5 and rot[17] < 0.35
    # zoom: contact spacing grows (log scale change), drag: translation, no scale
    assert zoom[14] > 0.1 and abs(drag[14]) < 0.05
    assert drag[12] > 0.2


def test_feature_vectors_are_finite_and_sized_with_no_hand():
    recs = records("open_hand", 3) + [None]
    assert static_features(recs, 12).shape == (static_size(12),)
    assert np.all(np.isfinite(dynamic_features(recs, 12, 4)))
    empty = static_features([None, None], 12)
    assert np.all(np.isfinite(empty)) and empty.shape == (static_size(12),)


def test_static_features_do_not_tell_left_from_right_hands():
    from plugins.gestures.features import select_static

    def feats(name, left):
        recs = records(name, 2, left=left, theta_deg=-60.0)
        return select_static(static_features(recs, P.n_harmonics), 2, P.n_harmonics)[0]

    right, left, other = feats("l_shape", False), feats("l_shape", True), feats("open_hand", False)
    assert np.linalg.norm(right - left) < 0.35 * np.linalg.norm(right - other)
