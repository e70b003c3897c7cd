"""Identities for hands and contacts from frame to frame: one id per object for as long
as it stays on the table.

Each frame, the measured positions are assigned to the live tracks' *predicted* positions
by minimum total distance (Hungarian assignment, ``scipy.optimize.linear_sum_assignment``)
within a gate; a track that finds no measurement coasts on its prediction for
``grace_frames`` frames before its id dies (a hand missed by one frame's segmentation keeps
its id); ids are never reused. Positions are smoothed by an alpha-beta filter (position
and velocity, Kalman's steady state for a constant-velocity target).

A hand's tracked position is the centroid of its outline (the blob's centre, as TUIO
2Dblb expects), mapped to table mm when a camera -> table mapping is given: the palm centre
(the distance transform's maximum) jumps between near-equal maxima of an open hand and is
kept for the gesture features only.

``Tracking.update(t_s, hands, contacts)`` -> ``TrackFrame``: the hands' and contacts'
tracks (aligned with the inputs) and every live track, the contacts renamed to their track
ids. ``Announcer`` says when a gesture starts (once per hand track and name).
"""

from __future__ import annotations

import itertools
import math
from collections.abc import Callable, Iterable, Sequence
from dataclasses import dataclass, replace

import numpy as np
from scipy.optimize import linear_sum_assignment

from console.core.types import Contact, Gesture, Hand

ToMm = Callable[[np.ndarray], np.ndarray]


@dataclass
class Track:
    """One followed object: ``id``, smoothed position ``x``, ``y`` and velocity ``vx``,
    ``vy`` (units per second; ``pos`` and ``vel`` as arrays), ``angle`` (rad) and
    ``rot_vel``; ``accel``/``rot_accel`` the last changes of speed and rotation speed per
    second; ``missed`` frames since last seen. Plain floats: a frame's few tracks cost
    microseconds, not the tens numpy's per-call overhead on 2-element arrays takes."""

    id: int
    x: float
    y: float
    t_s: float
    vx: float = 0.0
    vy: float = 0.0
    angle: float = 0.0
    rot_vel: float = 0.0
    accel: float = 0.0
    rot_accel: float = 0.0
    missed: int = 0
    frames: int = 1

    @property
    def pos(self) -> np.ndarray:
        """The position as a new array ``[x, y]``."""
        return np.array((self.x, self.y))

    @property
    def vel(self) -> np.ndarray:
        """The velocity as a new array ``[vx, vy]``."""
        return np.array((self.vx, self.vy))

    @property
    def speed(self) -> float:
        return math.hypot(self.vx, self.vy)

    def predict(self, t_s: float) -> tuple[float, float]:
        """The position expected at ``t_s`` (constant velocity; never backwards)."""
        dt = max(t_s - self.t_s, 0.0)
        return self.x + self.vx * dt, self.y + self.vy * dt


def _points(pts: Sequence[Sequence[float]]) -> list[tuple[float, float]]:
    """``pts`` as (x, y) float pairs (an (n, 2) array, or any sequence of pairs)."""
    if isinstance(pts, np.ndarray):
        return [(a, b) for a, b in np.asarray(pts, float).reshape(-1, 2).tolist()]
    return [(float(p[0]), float(p[1])) for p in pts]


def _fewest(d: list[list[float]], live: list[Track], gate: float) -> dict[int, Track]:
    """``linear_sum_assignment``'s pairing of a few points (rows of ``d``) and tracks
    (columns), out-of-gate distances costing 1e9, found by trying every one-to-one
    pairing of the smaller side (at most 3 x 3: six, instead of the solver's call and its
    arrays); only pairs within the gate are kept."""
    n, m = len(d), len(d[0])
    cost = [[v if v <= gate else 1e9 for v in row] for row in d]
    if n == m == 2:  # two and two (a grip's fingertips): straight unless crossing is less
        (a, b), (c, e) = cost
        best = ((0, 1), (1, 0)) if b + c < a + e else ((0, 0), (1, 1))
        return {i: live[j] for i, j in best if d[i][j] <= gate}
    if n <= m:
        pairs = [tuple(enumerate(cols)) for cols in itertools.permutations(range(m), n)]
    else:
        pairs = [
            tuple((i, j) for j, i in enumerate(rows))
            for rows in itertools.permutations(range(n), m)
        ]
    best = min(pairs, key=lambda ps: sum(cost[i][j] for i, j in ps))
    return {i: live[j] for i, j in best if d[i][j] <= gate}


class IdTracker:
    """Tracks with ids for points (Hungarian assignment on predicted positions).

    ``gate``: the farthest a measurement may be from a prediction (the points' units);
    ``grace_frames``: frames a track coasts unseen before it dies; ``alpha``/``beta``:
    the position and velocity gains of the alpha-beta filter (1, 1: no smoothing);
    ``ids``: the id counter (shared between trackers so ids are unique across them).
    """

    def __init__(
        self,
        gate: float,
        *,
        grace_frames: int = 6,
        alpha: float = 0.5,
        beta: float = 0.1,
        ids: Callable[[], int] | None = None,
    ) -> None:
        if gate <= 0 or grace_frames < 0 or not (0 < alpha <= 1) or not (0 <= beta <= 2):
            raise ValueError("tracker: gate > 0, grace_frames >= 0, 0 < alpha <= 1, 0 <= beta <= 2")
        self.gate, self.grace = float(gate), int(grace_frames)
        self.alpha, self.beta = float(alpha), float(beta)
        self.tracks: dict[int, Track] = {}
        if ids is None:
            counter = iter(range(1 << 62))
            ids = counter.__next__
        self._ids = ids

    def update(
        self, t_s: float, pts: Sequence[Sequence[float]], angles: Sequence[float] | None = None
    ) -> list[Track]:
        """Assign ``pts`` to tracks (a new id for a point no track claims); returns the
        points' tracks in order. Tracks unseen for more than ``grace_frames`` die."""
        xy = _points(pts)
        angs = [0.0] * len(xy) if angles is None else [float(a) for a in angles]
        return self._update(t_s, xy, angs)

    def _update(self, t_s: float, xy: Sequence[Sequence[float]], angs: list[float]) -> list[Track]:
        """``update`` of (x, y) float pairs and their angles."""
        tracks = self.tracks
        match = self._match(t_s, xy, list(tracks.values())) if tracks and xy else {}
        out: list[Track] = []
        for i, (x, y) in enumerate(xy):
            tr = match.get(i)
            if tr is None:
                tr = Track(self._ids(), x, y, t_s, angle=angs[i])
                tracks[tr.id] = tr
            else:
                self._correct(tr, t_s, x, y, angs[i])
            out.append(tr)
        if len(tracks) > len(out):  # some track went unseen (each seen one is in out once)
            self.coast({tr.id for tr in out})
        return out

    def coast(self, seen: set[int] | frozenset[int] = frozenset()) -> None:
        """A frame in which the tracks not in ``seen`` went unseen: each coasts one
        frame more, or dies after ``grace_frames``."""
        for tid, tr in list(self.tracks.items()):
            if tid not in seen:
                tr.missed += 1
                if tr.missed > self.grace:
                    del self.tracks[tid]

    def _match(
        self, t_s: float, xy: Sequence[Sequence[float]], live: list[Track]
    ) -> dict[int, Track]:
        """Point index -> its track: the least total distance to the tracks' predictions,
        within the gate."""
        # each track's ``predict(t_s)``, written out (a call less per track)
        pred = [(tr.x + tr.vx * (dt := max(t_s - tr.t_s, 0.0)), tr.y + tr.vy * dt) for tr in live]
        d = [[math.hypot(x - px, y - py) for px, py in pred] for x, y in xy]
        gate = self.gate
        if len(d) == 1 and len(live) == 1:  # one and one: the solver's answer
            return {0: live[0]} if d[0][0] <= gate else {}
        if len(xy) <= 3 and len(live) <= 3:  # a few: every pairing tried
            return _fewest(d, live, gate)
        dist = np.array(d)
        cost = np.where(dist <= gate, dist, 1e9)  # out of the gate: only if forced
        rows, cols = linear_sum_assignment(cost)
        return {int(i): live[j] for i, j in zip(rows, cols, strict=True) if dist[i, j] <= gate}

    def _correct(self, tr: Track, t_s: float, x: float, y: float, angle: float) -> None:
        dt = max(t_s - tr.t_s, 1e-6)
        vx, vy = tr.vx, tr.vy
        px, py = tr.x + vx * dt, tr.y + vy * dt
        rx, ry = x - px, y - py
        a, g = self.alpha, self.beta / dt
        tr.x, tr.y = px + a * rx, py + a * ry
        tr.vx, tr.vy = vx2, vy2 = vx + g * rx, vy + g * ry
        tr.accel = (math.hypot(vx2, vy2) - math.hypot(vx, vy)) / dt  # the speed's change
        rv = math.remainder(angle - tr.angle, 2 * math.pi) / dt
        tr.rot_accel = (rv - tr.rot_vel) / dt
        tr.angle, tr.rot_vel = angle, rv
        tr.t_s, tr.missed, tr.frames = t_s, 0, tr.frames + 1


def outline_centroid(contour_px: np.ndarray) -> tuple[float, float] | None:
    """Area centroid of a closed outline (shoelace moments); ``None`` if degenerate."""
    c = np.asarray(contour_px, float).reshape(-1, 2)
    if len(c) < 3:
        return None
    cn = np.concatenate((c[1:], c[:1]))  # each point's successor
    cross = c[:, 0] * cn[:, 1] - cn[:, 0] * c[:, 1]
    a = cross.sum() / 2.0
    if abs(a) < 1e-9:
        return None
    # both moments in one product; on a pixel outline (integers) every sum is exact, so
    # any order of summing gives the same bits
    mx, my = (cross @ (c + cn)).tolist()
    return mx / (6 * a), my / (6 * a)


@dataclass(frozen=True)
class TrackFrame:
    """One frame's tracking: ``hands``/``contacts`` (the frame's objects, contacts
    renamed to their track ids), ``hand_tracks``/``contact_tracks`` aligned with them,
    ``live_hands``/``live_contacts`` every live track (coasting ones included), ``in_mm``
    (positions in table mm; else camera px)."""

    t_s: float
    hands: tuple[Hand, ...]
    contacts: tuple[Contact, ...]
    hand_tracks: tuple[Track, ...]
    contact_tracks: tuple[Track, ...]
    live_hands: tuple[Track, ...]
    live_contacts: tuple[Track, ...]
    in_mm: bool

    def hand_id(self, hand: Hand | None) -> int:
        """The track id of ``hand`` (one of this frame's, else the nearest live hand
        track to its palm centre), -1 if none."""
        if hand is None:
            return -1
        for h, tr in zip(self.hands, self.hand_tracks, strict=True):
            if h is hand:
                return tr.id
        if not self.live_hands:
            return -1
        p = hand.center_mm if self.in_mm and hand.center_mm is not None else hand.center_px
        px, py = float(p[0]), float(p[1])
        d = [(math.hypot(tr.x - px, tr.y - py), tr.id) for tr in self.live_hands]
        return min(d)[1]


def _renamed(c: Contact, new_id: int) -> Contact:
    """``dataclasses.replace(c, id=new_id)``; a ``Contact``'s fields written out (a third
    of ``replace``'s cost, which looks the fields up on every call)."""
    if type(c) is Contact:
        return Contact(new_id, c.pos_px, c.pos_mm, c.area_px)
    return replace(c, id=new_id)


def _with_contacts(h: Hand, contacts: tuple[Contact, ...]) -> Hand:
    """``dataclasses.replace(h, contacts=contacts)``, a ``Hand``'s fields written out."""
    if type(h) is Hand:
        return Hand(
            h.contour_px, h.center_px, h.radius_px, h.angle_deg, h.shape, contacts, h.center_mm
        )
    return replace(h, contacts=contacts)


class Tracking:
    """Hands and contacts followed with ids (unique across both).

    ``to_mm``: camera px -> table mm (``None``: hands at their ``center_mm`` when they
    have one, contacts at ``pos_mm``; else px). Gates and grace in mm at 60 fps.
    """

    def __init__(
        self,
        to_mm: ToMm | None = None,
        *,
        hand_gate_mm: float = 90.0,
        contact_gate_mm: float = 20.0,
        hand_grace_frames: int = 6,
        contact_grace_frames: int = 3,
    ) -> None:
        self.to_mm = to_mm
        counter = iter(range(1 << 62))
        self.hands = IdTracker(hand_gate_mm, grace_frames=hand_grace_frames, ids=counter.__next__)
        self.contacts = IdTracker(
            contact_gate_mm, grace_frames=contact_grace_frames, alpha=0.7, ids=counter.__next__
        )

    def _hand_points(self, hands: Sequence[Hand]) -> tuple[list[list[float]], bool]:
        if not hands:
            return [], True
        if self.to_mm is not None:
            px = []
            for h in hands:
                c = outline_centroid(h.contour_px)
                px.append(c if c is not None else h.center_px)
            pts, in_mm = self.to_mm(np.asarray(px, float)), True
        elif all(h.center_mm is not None for h in hands):
            pts, in_mm = [h.center_mm for h in hands], True
        else:
            pts, in_mm = [h.center_px for h in hands], False
        return np.asarray(pts, float).reshape(-1, 2).tolist(), in_mm  # [x, y] pairs

    def update(self, t_s: float, hands: Sequence[Hand], contacts: Sequence[Contact]) -> TrackFrame:
        hand_tracks, contact_tracks = self.hands, self.contacts
        if not hands and not contacts:  # the empty table: the live tracks coast
            hand_tracks.coast()
            contact_tracks.coast()
            live_h, live_c = (
                tuple(hand_tracks.tracks.values()),
                tuple(contact_tracks.tracks.values()),
            )
            return TrackFrame(t_s, (), (), (), (), live_h, live_c, True)
        hpts, in_mm = self._hand_points(hands)
        htr = hand_tracks._update(t_s, hpts, [math.radians(h.angle_deg) for h in hands])
        if contacts:
            cmm = [c.pos_mm if in_mm and c.pos_mm is not None else c.pos_px for c in contacts]
            ctr = contact_tracks.update(t_s, cmm)
        else:
            contact_tracks.coast()
            ctr = []
        renamed = {id(c): _renamed(c, tr.id) for c, tr in zip(contacts, ctr, strict=True)}
        by_px = {c.pos_px: renamed[id(c)] for c in contacts}  # a hand's contacts are
        hands_out = [  # the frame's blobs (the same pixel position), renamed alike
            _with_contacts(h, tuple(by_px.get(c.pos_px, c) for c in h.contacts))
            if h.contacts
            else h
            for h in hands
        ]
        return TrackFrame(
            t_s,
            tuple(hands_out),
            tuple(renamed[id(c)] for c in contacts),
            tuple(htr),
            tuple(ctr),
            tuple(hand_tracks.tracks.values()),
            tuple(contact_tracks.tracks.values()),
            in_mm,
        )


class Announcer:
    """A gesture is announced once when it starts: ``update(gesture, hand_id, live)``
    returns it the first time its name is seen on that hand track, ``None`` after (while
    it lasts, through frames where recognition drops it, and after another gesture of
    the same hand: once per name per placement of a hand); a hand's memory ends with its
    track (``live``: the live hand track ids). Without a hand (``hand_id`` -1) a gesture
    ends after ``grace_frames`` frames without it."""

    def __init__(self, grace_frames: int = 6) -> None:
        self.grace = int(grace_frames)
        self._said: dict[int, set[str]] = {}  # hand track id -> gestures announced
        self._loose: dict[str, int] = {}  # handless gesture -> frames since last seen

    def update(
        self, gesture: Gesture | None, hand_id: int, live: Iterable[int] = ()
    ) -> Gesture | None:
        live_ids = set(live) | ({hand_id} if hand_id >= 0 else set())
        self._said = {h: n for h, n in self._said.items() if h in live_ids}
        name = gesture.name if gesture is not None and hand_id < 0 else None
        for k in list(self._loose):
            if k != name:
                self._loose[k] += 1
                if self._loose[k] > self.grace:
                    del self._loose[k]
        if gesture is None:
            return None
        if hand_id >= 0:
            said = self._said.setdefault(hand_id, set())
            if gesture.name in said:
                return None
            said.add(gesture.name)
            return gesture
        new = gesture.name not in self._loose
        self._loose[gesture.name] = 0
        return gesture if new else None
