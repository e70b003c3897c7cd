"""Scripted gestures of the camera twin (paper Fig. 3): poses over time, per subject.

A *take* is one performance of a gesture: where on the table, from which side, which
hand, how fast, in which direction. ``plan_take`` draws one from a subject's style and
a generator; ``take_pose(take, t_s)`` gives the hand pose ``t_s`` seconds after the
gesture's first frame (the first frame already shows the gesture: contact made, and
for dynamic gestures motion under way).
"""

from __future__ import annotations

import functools
from dataclasses import dataclass, field, replace

import numpy as np

from .hand import FINGERS, FingerPose, HandPose, Subject, hand_pieces

STATIC: tuple[str, ...] = ("one_finger", "two_finger", "l_shape", "closed_hand", "open_hand")
DYNAMIC: tuple[str, ...] = ("drag", "rotate", "spread_pile", "wipe", "zoom")
GESTURES: tuple[str, ...] = STATIC + DYNAMIC


@dataclass(frozen=True)
class Take:
    """One performance of a gesture."""

    gesture: str
    subject: Subject
    side: str
    wrist_mm: tuple[float, float]
    angle_deg: float
    rate: float  # motion speed (mm/s, deg/s, or pose fraction per second)
    direction: float  # path direction (deg, relative to the hand) or +-1
    variant: str = ""  # "in"/"out", "spread"/"pile", "cw"/"ccw"
    jitter: tuple[float, ...] = field(default=(0.0,) * 8)  # per-take pose variation
    tremor: bool = True
    seed: int = 0
    ease_s: float = 0.0  # time constant of the start from rest (0: full speed at once)


def _curled(s: Subject, j: float, lift_extra: float = 0.0) -> FingerPose:
    return FingerPose((70 + 8 * j, 95 - 6 * j, 45), 0.0, False, s.lift_mm + lift_extra)


def _point(j: float, abd: float = 0.0) -> FingerPose:
    return FingerPose((0.0, 12 + 8 * j, 8 + 4 * j), abd, True)


def _flat(abd: float) -> FingerPose:
    return FingerPose((0.0, 2.0, 2.0), abd, True)


def static_pose(gesture: str, s: Subject, j: tuple[float, ...]) -> tuple:
    """(palm heights, finger poses) of a static gesture; ``j`` = per-take jitter in [-1, 1]."""
    sp = s.spread_deg
    hp = s.palm_lift_mm + 4 * j[0]
    thumb_up = FingerPose((25, 35, 25), -5 + 5 * j[1], False, s.lift_mm + 6)
    if gesture == "one_finger":
        return (hp + 5, hp), (
            thumb_up,
            _point(j[2]),
            _curled(s, j[3]),
            _curled(s, j[3]),
            _curled(s, j[4]),
        )
    if gesture == "two_finger":
        return (hp + 5, hp), (
            thumb_up,
            _point(j[2], -4 * sp + 4 * j[5]),
            _point(j[3], 4 * sp + 4 * j[6]),
            _curled(s, j[4], 3),
            _curled(s, j[4], 3),
        )
    if gesture == "l_shape":
        hl = 10 + 3 * j[0]
        return (hl + 4, hl), (
            _flat(-38 * sp + 9 * j[1]),
            _flat(-2 + 4 * j[2]),
            _curled(s, j[3]),
            _curled(s, j[3]),
            _curled(s, j[4]),
        )
    if gesture == "closed_hand":
        closed = (22 + 3 * j[1], 5 + j[2], 0.0, -4 + j[3], -10 + j[4])
        return (0.0, 0.0), tuple(
            _flat(a + t) for a, t in zip(closed, s.closed_turn_deg, strict=True)
        )
    if gesture == "open_hand":
        sp = s.spread_deg if s.open_spread is None else s.open_spread
        return (0.0, 0.0), (
            _flat(-25 * sp + 6 * j[1]),
            _flat(-12 * sp + 4 * j[2]),
            _flat(2 * j[5]),
            _flat(9 * sp + 4 * j[3]),
            _flat(20 * sp + 5 * j[4]),
        )
    raise ValueError(f"not a static gesture: {gesture!r}")


def _lerp(a: float, b: float, p: float) -> float:
    return a + (b - a) * p


def _pinch_fingers(s: Subject, p: float, j) -> tuple:
    """Thumb and index touching; ``p`` = 0 pinched together .. 1 spread apart."""
    thumb = FingerPose(
        (_lerp(25, 5, p), _lerp(30, 5, p), _lerp(25, 5, p)), _lerp(20, -25, p) + 3 * j[1], True
    )
    index = FingerPose((0.0, _lerp(55, 10, p), _lerp(35, 5, p)), _lerp(-8, 0, p), True)
    c = _curled(s, j[3], 4)
    return (thumb, index, c, c, c)


def _pinch_middle(s: Subject, pose: HandPose) -> np.ndarray:
    """The middle of the thumb's and the index's touch (mm)."""
    return (np.array(_tip(s, pose, "thumb")) + np.array(_tip(s, pose, "index"))) / 2


def _piled(s: Subject) -> np.ndarray:
    """Abductions (deg) of a pile: each finger closed in on its neighbours."""
    opened = np.array((-28.0, -12.0, 0.0, 10.0, 22.0)) * s.spread_deg
    return opened * 0.1 + [12.0, 0.0, 0.0, 0.0, 0.0]


@functools.lru_cache(maxsize=64)
def _gathered(s: Subject) -> tuple[float, ...]:
    """Abductions (deg) turning each finger of a pile (``_piled``) so that its tip
    points at the centroid of the piled tips (found on the hand's own geometry):
    fingertips brought together until they touch."""
    piled = _piled(s)
    flex = (0.0, 70.0, 40.0)
    pose = HandPose((0.0, 0.0), 90.0, "right", palm_h_mm=(20.0, 15.0),
                    fingers=tuple(FingerPose(flex, float(a), True) for a in piled))  # fmt: skip
    tips = {c["finger"]: np.array(c["pos_mm"]) for c in hand_pieces(s, pose).contacts}
    if len(tips) < 5:
        return tuple(float(a) for a in piled)
    base = np.asarray(s.mcp_uv, dtype=float)  # at angle 90 the table's mm are the hand's uv
    tip = np.array([tips[f] for f in FINGERS])
    now = np.arctan2(*(tip - base).T)
    want = np.arctan2(*(tip.mean(axis=0) - base).T)
    return tuple(float(a) for a in piled + np.degrees(want - now))


def _five_fingers(s: Subject, p: float, j) -> tuple:
    """All five tips touching; ``p`` = 0 piled together .. 1 spread out. Piled, the
    tips close in on each other, and on one point as far as ``s.gather`` says."""
    opened = np.array((-28.0, -12.0, 0.0, 10.0, 22.0)) * s.spread_deg
    piled = _piled(s)
    if s.gather > 0:
        piled = piled + s.gather * (np.array(_gathered(replace(s, gather=0.0))) - piled)
    f = []
    for k in range(5):
        flex = (0.0, _lerp(70, 12, p), _lerp(40, 8, p))
        abd = _lerp(float(piled[k]), float(opened[k]), p)
        f.append(FingerPose(flex, abd + j[k] * 1.5, True))
    return tuple(f)


def _unit(deg: float) -> np.ndarray:
    a = np.radians(deg)
    return np.array([np.cos(a), np.sin(a)])


def eased_s(t_s: float, ease_s: float) -> float:
    """Time at full speed equivalent to ``t_s`` of a motion starting from rest with
    velocity ``1 - exp(-t / ease_s)`` (integrated)."""
    if ease_s <= 0:
        return t_s
    return t_s - ease_s * (1.0 - float(np.exp(-t_s / ease_s)))


#: How far a long take goes before it turns back (drag/wipe mm, rotate deg): a held
#: gesture sweeps back and forth instead of leaving the table or spinning round.
SWEEP = {"drag": 150.0, "wipe": 130.0, "rotate": 100.0}


def _sweep(x: float, span: float) -> float:
    """Triangle wave: 0 -> span -> 0 -> ... as ``x`` grows (identity on [0, span])."""
    x = x % (2 * span)
    return x if x <= span else 2 * span - x


def _reflect01(x: float) -> float:
    """Fold ``x`` back into [0, 1] (a pose fraction that keeps going turns back)."""
    return _sweep(x, 1.0)


def take_pose(take: Take, t_s: float, rng: np.random.Generator | None = None) -> HandPose:
    """The hand pose ``t_s`` seconds into a take (tremor from ``rng`` when given).
    Dynamic gestures start from rest and reach their speed within ``take.ease_s``."""
    s, j, g = take.subject, take.jitter, take.gesture
    tm = eased_s(t_s, take.ease_s)  # motion time
    base = HandPose(take.wrist_mm, take.angle_deg, take.side)
    if g in STATIC:
        palm, fingers = static_pose(g, s, j)
        pose = replace(base, palm_h_mm=palm, fingers=fingers)
    elif g == "drag":
        palm, fingers = static_pose("one_finger", s, j)
        d = np.radians(take.angle_deg + take.direction)
        dist = _sweep(take.rate * tm, SWEEP["drag"])
        curv = s.curvature + 0.002 * j[6]
        # arc of curvature ``curv`` starting along ``d``
        if abs(curv) < 1e-6:
            off = dist * np.array([np.cos(d), np.sin(d)])
        else:
            r = 1 / curv
            off = r * np.array(
                [np.sin(d + dist * curv) - np.sin(d), np.cos(d) - np.cos(d + dist * curv)]
            )
        pose = replace(base, palm_h_mm=palm, fingers=fingers).moved(
            tuple(off), 8 * j[7] * dist / max(take.rate, 1.0)
        )
    elif g == "rotate":
        hp = s.palm_lift_mm - 5
        c = _curled(s, j[3], 2)
        thumb = FingerPose((10, 15, 10), -15 + 4 * j[1], True)
        fingers = (thumb, _point(j[2], -6), c, c, c)
        pose = replace(base, palm_h_mm=(hp + 5, hp), fingers=fingers)
        thumb_at = np.array(_tip(s, pose, "thumb"))
        pivot = thumb_at + s.pivot * (np.array(_tip(s, pose, "index")) - thumb_at)
        w = take.direction * _sweep(take.rate * tm, SWEEP["rotate"])
        pose = _rotate_about(pose, pivot, w)
    elif g == "zoom":
        p0 = 0.15 + 0.1 * j[0] if take.variant == "in" else 0.85 + 0.1 * j[0]
        p = _reflect01(p0 + take.direction * take.rate * tm)
        hp = 0.7 * s.palm_lift_mm
        pose = replace(base, palm_h_mm=(hp + 5, hp), fingers=_pinch_fingers(s, p, j))
        if s.zoom_still > 0:  # the hand follows the tips' middle back to where it began
            start = replace(pose, fingers=_pinch_fingers(s, _reflect01(p0), j))
            pose = pose.moved(
                tuple(s.zoom_still * (_pinch_middle(s, start) - _pinch_middle(s, pose)))
            )
    elif g == "spread_pile":
        p0 = 0.1 + 0.08 * j[0] if take.variant == "spread" else 0.9 + 0.08 * j[0]
        p = _reflect01(p0 + take.direction * take.rate * tm)
        hp = 0.6 * s.palm_lift_mm
        pose = replace(base, palm_h_mm=(hp + 5, hp), fingers=_five_fingers(s, p, j))
        # the fingertips move, the hand keeps its middle tip roughly in place
    elif g == "wipe":
        palm, fingers = static_pose("closed_hand", s, j)
        pose = replace(base, palm_h_mm=palm, fingers=fingers)
        d = np.radians(take.angle_deg + take.direction)
        dist = _sweep(take.rate * tm, SWEEP["wipe"])
        off = dist * np.array([np.cos(d), np.sin(d)])
        pose = pose.moved(tuple(off), 25 * j[7] * dist / max(take.rate, 1.0))
    else:
        raise ValueError(f"unknown gesture {g!r}")
    if take.tremor and rng is not None:
        pose = pose.moved(tuple(rng.normal(0, s.tremor_mm, 2)), float(rng.normal(0, 0.15)))
    return pose


@functools.lru_cache(maxsize=256)
def _tip(s: Subject, pose: HandPose, finger: str) -> tuple[float, float]:
    """Where ``finger`` touches (or its tip); cached: a turning hand's pivot, every frame."""
    geo = hand_pieces(s, pose)
    for c in geo.contacts:
        if c["finger"] == finger:
            return c["pos_mm"]
    x, y, _ = geo.tips_mm[finger]
    return (x, y)


def _rotate_about(pose: HandPose, pivot: np.ndarray, d_deg: float) -> HandPose:
    a = np.radians(d_deg)
    rot = np.array([[np.cos(a), -np.sin(a)], [np.sin(a), np.cos(a)]])
    w = pivot + rot @ (np.asarray(pose.wrist_mm) - pivot)
    return replace(pose, wrist_mm=(float(w[0]), float(w[1])), angle_deg=pose.angle_deg + d_deg)


#: Speeds (per second) at subject speed 1: mm/s, deg/s, or pose fraction/s.
RATES = {
    "drag": (150.0, 380.0),
    "rotate": (120.0, 300.0),
    "zoom": (1.6, 3.2),
    "spread_pile": (2.0, 4.0),
    "wipe": (300.0, 650.0),
}

#: Approach sides: (edge, heading of the fingers in the table frame).
SIDES = (("bottom", 90.0), ("top", 270.0), ("left", 0.0), ("right", 180.0))


def plan_take(
    gesture: str,
    subject: Subject,
    rng: np.random.Generator,
    table_mm: tuple[float, float],
    *,
    side: str | None = None,
    wrist_mm: tuple[float, float] | None = None,
    angle_deg: float | None = None,
    duration_s: float = 0.2,
    tremor: bool = True,
) -> Take:
    """Draw a take: position, approach side, speed and direction in the subject's style."""
    if gesture not in GESTURES:
        raise ValueError(f"unknown gesture {gesture!r}; use one of {', '.join(GESTURES)}")
    side = side or subject.side
    w, h = table_mm
    jitter = tuple(float(x) for x in rng.uniform(-1, 1, 8))
    edge_p = np.array([w, w, h, h]) / (2 * (w + h))
    _, heading = SIDES[int(rng.choice(4, p=edge_p))]
    angle = float(heading + rng.normal(0, 20)) if angle_deg is None else float(angle_deg)
    rate, direction, variant = 0.0, 0.0, ""
    if gesture in RATES:
        lo, hi = RATES[gesture]
        rate = float(rng.uniform(lo, hi) * subject.speed)
    if gesture == "drag":
        direction = float(rng.uniform(0, 360))
    elif gesture == "rotate":
        direction = float(rng.choice([-1.0, 1.0]))
        variant = "ccw" if direction > 0 else "cw"
    elif gesture == "zoom":
        variant = str(rng.choice(["in", "out"]))
        direction = 1.0 if variant == "in" else -1.0
    elif gesture == "spread_pile":
        variant = str(rng.choice(["spread", "pile"]))
        direction = 1.0 if variant == "spread" else -1.0
    elif gesture == "wipe":
        direction = float(rng.choice([-90.0, 90.0]) + rng.normal(0, 12))
    if wrist_mm is None:
        reach = subject.length_mm * 0.55
        travel = min(rate * duration_s, SWEEP[gesture]) if gesture in ("drag", "wipe") else 20.0
        margin = reach + travel + 25.0
        mx, my = min(margin, w / 2 - 1), min(margin, h / 2 - 1)
        center = np.array([rng.uniform(mx, w - mx), rng.uniform(my, h - my)])
        wrist = center - reach * _unit(angle)
        if gesture in ("drag", "wipe"):  # start behind so the path stays centred
            wrist -= 0.5 * travel * _unit(angle + direction)
        wrist_mm = (float(wrist[0]), float(wrist[1]))
    ease = float(subject.ease_s * rng.uniform(0.7, 1.3)) if gesture in DYNAMIC else 0.0
    return Take(
        gesture,
        subject,
        side,
        wrist_mm,
        angle,
        rate,
        direction,
        variant,
        jitter,
        tremor,
        int(rng.integers(0, 2**31)),
        ease,
    )
