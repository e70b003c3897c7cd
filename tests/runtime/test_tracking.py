"""Identities for hands and contacts (console.runtime.tracking)."""

from __future__ import annotations

from dataclasses import fields, replace

import cv2
import numpy as np
import pytest

from console.core.types import Contact, Gesture, Hand, HandShape
from console.runtime.tracking import (
    Announcer,
    IdTracker,
    Tracking,
    _fewest,
    _renamed,
    _with_contacts,
    outline_centroid,
)


def test_crossing_points_keep_their_ids_where_greedy_matching_swaps_them():
    # two points moving towards each other: greedy nearest-first pairing takes the one
    # short pair and forces the other far; the total-distance assignment does not
    tr = IdTracker(gate=50.0, alpha=1.0, beta=0.0)
    a, b = tr.update(0.0, [(0.0, 0.0), (30.0, 0.0)])
    # A moved to 18 (18 away from its track, 12 from B's), B moved to 45 (15 from B's)
    got = tr.update(1 / 60, [(18.0, 0.0), (45.0, 0.0)])
    assert [t.id for t in got] == [a.id, b.id]


def test_a_missed_frame_keeps_the_id_and_a_long_absence_ends_it():
    tr = IdTracker(gate=20.0, grace_frames=3)
    (t0,) = tr.update(0.0, [(100.0, 100.0)])
    for k in range(1, 4):  # three frames without it: coasting, still live
        assert tr.update(k / 60, []) == [] and t0.id in tr.tracks
    (t1,) = tr.update(4 / 60, [(101.0, 100.0)])
    assert t1.id == t0.id
    for k in range(5, 9):
        tr.update(k / 60, [])
    assert not tr.tracks
    (t2,) = tr.update(9 / 60, [(101.0, 100.0)])
    assert t2.id > t0.id  # ids are never reused


def test_out_of_the_gate_is_a_new_object():
    tr = IdTracker(gate=20.0)
    (a,) = tr.update(0.0, [(0.0, 0.0)])
    (b,) = tr.update(1 / 60, [(50.0, 0.0)])
    assert b.id != a.id and set(tr.tracks) == {a.id, b.id}


def test_the_filter_follows_a_constant_velocity_exactly_once_settled():
    # the alpha-beta filter's steady state for a constant-velocity target: no lag
    tr = IdTracker(gate=100.0, alpha=0.5, beta=0.1)
    v = np.array([120.0, -30.0])  # units per second
    for k in range(400):
        (t,) = tr.update(k / 60, [v * k / 60])
    assert t.pos == pytest.approx(v * 399 / 60, abs=1e-6)
    assert t.vel == pytest.approx(v, abs=1e-6)


def test_the_filter_reduces_noise_as_the_alpha_beta_theory_says():
    # Kalata (1984): steady-state position variance ratio of the alpha-beta filter
    a, b = 0.5, 0.1
    theory = (2 * a * a + 2 * b - 3 * a * b) / (a * (4 - 2 * a - b))
    rng = np.random.default_rng(1)
    tr = IdTracker(gate=1e6, alpha=a, beta=b)
    out = []
    for k in range(20000):
        (t,) = tr.update(k / 60, [rng.normal(0.0, 1.0, 2)])
        out.append(t.pos.copy())
    var = np.var(np.array(out[200:]), axis=0).mean()
    assert var == pytest.approx(theory, rel=0.05)


def test_outline_centroid_matches_opencv_moments():
    rng = np.random.default_rng(2)
    ang = np.sort(rng.uniform(0, 2 * np.pi, 40))
    r = rng.uniform(40, 90, 40)
    pts = np.c_[200 + r * np.cos(ang), 150 + r * np.sin(ang)]
    m = cv2.moments(pts.astype(np.float32))
    assert outline_centroid(pts) == pytest.approx((m["m10"] / m["m00"], m["m01"] / m["m00"]))
    assert outline_centroid(pts[::-1]) == pytest.approx(outline_centroid(pts))  # either turn
    assert outline_centroid(pts[:2]) is None
    assert outline_centroid(np.array([[0, 0], [1, 1], [2, 2]])) is None  # no area


def _hand(contour, palm_px, contacts=()):
    return Hand(
        np.asarray(contour, float), palm_px, 30.0, 0.0, HandShape.of(np.zeros(4), 0), contacts
    )


def test_a_hand_is_tracked_at_its_outline_centre_not_its_jumping_palm_centre():
    square = [[100, 100], [200, 100], [200, 200], [100, 200]]
    trk = Tracking(to_mm=lambda px: np.asarray(px, float) * 2.0)
    ids = set()
    for k in range(20):
        palm = (150.0, 130.0) if k % 2 else (150.0, 170.0)  # two near-equal maxima
        c = Contact(0, (120.0, 110.0), (240.0, 220.0))
        f = trk.update(k / 60, [_hand(square, palm, (c,))], [c])
        (t,) = f.hand_tracks
        ids.add(t.id)
        assert t.pos == pytest.approx((300.0, 300.0))  # mm of the square's centre
        # the hand's own contact and the frame's are the same blob: the same track id
        assert f.hands[0].contacts[0].id == f.contacts[0].id == f.contact_tracks[0].id
        assert f.hand_id(f.hands[0]) == t.id
    assert len(ids) == 1 and t.id != f.contacts[0].id  # unique across hands and contacts


def test_a_gesture_is_announced_when_it_starts():
    g = Gesture("two_finger", "static", 1.0, 0.0)
    r = Gesture("rotate", "dynamic", 1.0, 0.0)
    ann = Announcer(grace_frames=2)
    seq = [(g, 1, {1}), (g, 1, {1}), (None, -1, {1}), (None, -1, {1}), (None, -1, {1})]
    seq += [(g, 1, {1}), (g, 2, {1, 2}), (r, 1, {1, 2}), (g, 1, {1, 2})]
    seq += [(None, -1, {2}), (g, 3, {2, 3})]  # hand 1 left; hand 3 is a new placement
    seq += [(g, -1, ()), (None, -1, ()), (g, -1, ()), (None, -1, ())]  # no hand: grace
    seq += [(None, -1, ()), (None, -1, ()), (g, -1, ())]
    said = [ann.update(gk, hid, live) is not None for gk, hid, live in seq]
    # dropped by recognition on the same hand, or back after another gesture of that
    # hand: not again; another hand, another name, a new hand: each a start
    assert said[:11] == [True, False, False, False, False, False, True, True, False, False, True]
    assert said[11:] == [True, False, False, False, False, False, True]


def test_bench_tracking_sees_one_hand_and_two_fingertips(profile, plugins):
    from types import SimpleNamespace

    from console.benchmarks.tracking import run

    out = run(SimpleNamespace(profile=profile, pm=plugins), quick=True)
    rest = out["resting_hand"]
    assert rest["blob_sessions"] == 1 and out["two_fingers"]["contact_sessions"] == 2
    # the tracked centre is steadier than the palm centre it replaces for tracking
    assert rest["tracked_centre_step"]["p99_mm"] < rest["palm_centre_step"]["p50_mm"] + 1.0
    assert out["tracker"]["n"] == out["frames"] > 0


@pytest.mark.parametrize("seed", range(4))
def test_the_plain_float_tracker_gives_the_numpy_tracker_s_ids_and_positions(seed):
    # points that wander, cross, vanish for a while and appear: every frame's ids and
    # every live track the same; positions bit for bit, speeds' changes to the last bits
    from .plain_tracking import PlainIdTracker

    rng = np.random.default_rng(seed)
    tr, ref = IdTracker(25.0, grace_frames=3), PlainIdTracker(25.0, 3, 0.5, 0.1)
    pos = rng.uniform(0, 300, (5, 2))
    vel = rng.normal(0, 600, (5, 2))
    paths = 0
    for k in range(400):
        t_s = k / 60 + rng.uniform(0, 0.004)  # frame-rate jitter
        pos += vel / 60 + rng.normal(0, 1.5, (5, 2))
        shown = rng.random(5) < 0.8
        pts, angs = pos[shown], rng.uniform(-np.pi, np.pi, shown.sum())
        got, want = tr.update(t_s, pts, angs), ref.update(t_s, pts, angs)
        paths += len(got) > 1 and len(tr.tracks) > 1
        assert [t.id for t in got] == [t.id for t in want]
        assert sorted(tr.tracks) == sorted(ref.tracks)
        for a in tr.tracks.values():
            b = ref.tracks[a.id]
            assert (a.x, a.y, a.vx, a.vy) == (*b.pos, *b.vel)
            assert (a.angle, a.rot_vel, a.rot_accel, a.missed) == (
                b.angle,
                b.rot_vel,
                b.rot_accel,
                b.missed,
            )
            assert a.accel == pytest.approx(b.accel, rel=1e-12, abs=1e-9)
    assert paths > 100  # most frames assign several points among several tracks


@pytest.mark.parametrize("cls", [Contact, Hand])
def test_renaming_keeps_every_field_of_a_contact_and_a_hand(cls):
    # the renamed copies are written field by field: a field added to the class and
    # not copied fails here
    obj = cls(**{f.name: object() for f in fields(cls)})
    if cls is Contact:
        got, want = _renamed(obj, 9), replace(obj, id=9)
    else:
        got, want = _with_contacts(obj, ("c",)), replace(obj, contacts=("c",))
    assert type(got) is cls
    assert all(getattr(got, f.name) is getattr(want, f.name) for f in fields(cls))


def test_a_pixel_outline_s_centroid_is_the_plain_shoelace_s_bit_for_bit():
    # on integer pixels every sum is exact: the moments' one product gives the bits of
    # the plain shoelace sums (np.roll), which the frame loop's decisions keep
    rng = np.random.default_rng(3)
    for k in range(300):
        n = int(rng.integers(3, 1200))
        ang = np.sort(rng.uniform(0, 2 * np.pi, n))
        r = rng.uniform(5, 300, n)
        c = np.rint(np.c_[320 + r * np.cos(ang), 240 + r * np.sin(ang)])[:: 1 if k % 2 else -1]
        x, y = c[:, 0], c[:, 1]
        xn, yn = np.roll(x, -1), np.roll(y, -1)
        cross = x * yn - xn * y
        a = cross.sum() / 2.0
        want = (((x + xn) * cross).sum() / (6 * a), ((y + yn) * cross).sum() / (6 * a))
        assert outline_centroid(c) == want


def test_empty_frames_age_the_live_tracks_as_frames_with_nothing_seen():
    # the empty table's frames skip the matching (the tracks only coast): each live
    # track's misses, deaths after its grace and ids as a frame of nothing seen has them
    square = [[100, 100], [200, 100], [200, 200], [100, 200]]
    c = Contact(0, (120.0, 110.0), (240.0, 220.0))
    seen = ([_hand(square, (150.0, 150.0), (c,))], [c])
    fast, ref = Tracking(to_mm=lambda px: np.asarray(px, float)), Tracking()
    ref.to_mm = fast.to_mm
    frames = [seen] * 3 + [((), ())] * 2 + [seen] + [((), ())] * 9 + [seen]
    for k, (hands, contacts) in enumerate(frames):
        got = fast.update(k / 60, hands, contacts)
        # the general path: the trackers' update with no points
        ref_h = ref.hands.update(k / 60, np.zeros((0, 2)), []) if not hands else None
        want = ref.update(k / 60, hands, contacts) if hands else None
        if want is None:
            ref.contacts.update(k / 60, [])
            assert got.hands == got.contacts == got.hand_tracks == got.contact_tracks == ()
            assert ref_h == [] and got.in_mm
        else:
            assert [t.id for t in got.hand_tracks] == [t.id for t in want.hand_tracks]
        for a, b in ((fast.hands, ref.hands), (fast.contacts, ref.contacts)):
            assert [(t.id, t.missed, t.x, t.y) for t in a.tracks.values()] == [
                (t.id, t.missed, t.x, t.y) for t in b.tracks.values()
            ]
    assert got.hand_tracks[0].id > 1  # the first hand's track died in the long gap


def test_two_points_and_two_tracks_pair_as_trying_both_pairings_does():
    # the 2 x 2 case is decided by one comparison: the pairing of the least total cost
    # (out of the gate 1e9), the straight one on a tie, as min over both pairings has it
    import itertools

    rng = np.random.default_rng(5)
    live = ["a", "b"]
    for _ in range(2000):
        d = rng.choice([0.0, 3.0, 5.0, 8.0, 25.0, 40.0], (2, 2)).tolist()
        cost = [[v if v <= 20.0 else 1e9 for v in row] for row in d]
        best = min(
            (tuple(enumerate(cols)) for cols in itertools.permutations(range(2), 2)),
            key=lambda ps: sum(cost[i][j] for i, j in ps),
        )
        assert _fewest(d, live, 20.0) == {i: live[j] for i, j in best if d[i][j] <= 20.0}
