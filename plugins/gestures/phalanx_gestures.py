"""The ten gestures acted out for the phalanx renderer (``phalanx_renderer``).

Static gestures: a resting hand with a small tremor. Dynamic ones: the motion over the
frames (drag: one finger sliding; rotate: thumb and index turning about their midpoint;
spread_pile: five tips spreading or gathering; wipe: a flat hand sweeping; zoom: thumb
and index moving apart or together). Every take draws its place, approach side, speed,
direction and a little pose jitter from a generator. Two more of a take's ways are left
at their plain values unless given (domain randomisation): ``ease_s`` starts its motion
from rest, reaching its speed with that time constant (``eased_s``), as a person starting
a gesture slowly does; ``pivot`` is where a rotate turns about, along the line from the
thumb's tip (0) to the index's (1; 0.5 the midpoint, the plain take).
"""

from __future__ import annotations

import math
from dataclasses import dataclass, replace

import numpy as np

from .dataset import DYNAMIC, STATIC
from .phalanx_renderer import HEIGHT, PX_PER_MM, WIDTH, Finger, Pose, Subject, hand_parts

FPS = 60.0
#: speed ranges per dynamic gesture: mm/s (drag, wipe), deg/s (rotate), pose fraction/s
SPEEDS = {
    "drag": (150.0, 400.0),
    "rotate": (100.0, 300.0),
    "zoom": (1.5, 3.0),
    "spread_pile": (2.0, 4.0),
    "wipe": (300.0, 650.0),
}


@dataclass(frozen=True)
class Take:
    """One performance: where, from which side, how fast, which way, and jitter."""

    gesture: str
    centre_px: tuple[float, float]
    angle_deg: float
    speed: float
    direction: float  # deg (drag, wipe) or +-1 (rotate, zoom, spread_pile)
    start: float  # starting pose fraction (zoom, spread_pile)
    jitter: tuple[float, ...]
    ease_s: float = 0.0  # time constant of the start from rest (0: full speed at once)
    pivot: float = 0.5  # a rotate's pivot from the thumb's tip (0) to the index's (1)


def eased_s(t_s: float, ease_s: float) -> float:
    """Motion time at ``t_s`` of a start from rest whose velocity grows as
    ``1 - exp(-t / ease_s)`` (its integral; ``t_s`` itself for ``ease_s`` 0)."""
    if ease_s <= 0:
        return t_s
    return t_s - ease_s * (1.0 - math.exp(-t_s / ease_s))


def _curled(j: float) -> Finger:
    return Finger(0.0, (65.0 + 6 * j, 90.0, 50.0), False)


def _point(j: float, abd: float = 0.0) -> Finger:
    return Finger(abd, (0.0, 14.0 + 8 * j, 8.0 + 3 * j), True)


def _flat(abd: float) -> Finger:
    return Finger(abd, (0.0, 2.0, 2.0), False, True)


def _thumb_up(j: float) -> Finger:
    return Finger(-25.0 + 6 * j, (25.0, 30.0, 20.0), False)


def _lerp(a: float, b: float, p: float) -> float:
    return a + (b - a) * p


def static_pose(gesture: str, s: Subject, j: tuple[float, ...]) -> tuple[float, tuple]:
    """(palm height mm, five fingers) of a static gesture."""
    sp = s.spread
    palm = (28.0 + 6 * j[0]) * s.hover
    if gesture == "one_finger":
        c = _curled(j[3])
        return palm, (_thumb_up(j[1]), _point(j[2]), c, c, _curled(j[4]))
    if gesture == "two_finger":
        c = _curled(j[4])
        return palm, (
            _thumb_up(j[1]),
            _point(j[2], -5 * sp + 2 * j[5]),
            _point(j[3], 5 * sp + 2 * j[6]),
            c,
            c,
        )
    if gesture == "l_shape":
        c = _curled(j[3])
        return (11.0 + 3 * j[0]) * s.hover, (
            Finger(-62 * sp + 6 * j[1], (0.0, 5.0, 5.0), True),
            Finger(-2 + 3 * j[2], (0.0, 4.0, 3.0), True),
            c,
            c,
            _curled(j[4]),
        )
    if gesture == "closed_hand":
        return 0.0, (
            _flat(-18 + 3 * j[1]),
            _flat(3 + j[2]),
            _flat(0.0),
            _flat(-3 + j[3]),
            _flat(-7 + j[4]),
        )
    if gesture == "open_hand":
        return 0.0, (
            _flat(-55 * sp + 5 * j[1]),
            _flat(-16 * sp + 3 * j[2]),
            _flat(2 * j[5]),
            _flat(12 * sp + 3 * j[3]),
            _flat(26 * sp + 4 * j[4]),
        )
    raise ValueError(f"not a static gesture: {gesture!r}")


def pinch(p: float, j: tuple[float, ...]) -> tuple[Finger, ...]:
    """Thumb and index tips on the glass; ``p`` 0 = together .. 1 = apart."""
    thumb = Finger(_lerp(-12, -55, p) + 3 * j[1], (_lerp(20, 0, p), _lerp(30, 6, p), 15.0), True)
    index = Finger(_lerp(-14, 0, p), (0.0, _lerp(60, 12, p), _lerp(35, 6, p)), True)
    c = _curled(j[3])
    return (thumb, index, c, c, c)


def five_tips(p: float, s: Subject, j: tuple[float, ...]) -> tuple[Finger, ...]:
    """All five tips on the glass; ``p`` 0 = piled together .. 1 = spread out."""
    opened = (-55.0, -16.0, 0.0, 12.0, 24.0)
    piled = (-14.0, -5.0, 0.0, 4.0, 9.0)
    out = []
    for i in range(5):
        abd = _lerp(piled[i], opened[i] * s.spread, p) + 1.5 * j[i]
        flex = (0.0, _lerp(70, 12, p), _lerp(40, 8, p))
        out.append(Finger(abd, flex, True))
    return tuple(out)


def _rotate_about(centre: np.ndarray, pivot: np.ndarray, deg: float) -> np.ndarray:
    a = math.radians(deg)
    rot = np.array([[math.cos(a), -math.sin(a)], [math.sin(a), math.cos(a)]])
    return pivot + rot @ (centre - pivot)


def _unit(deg: float) -> np.ndarray:
    return np.array([math.cos(math.radians(deg)), math.sin(math.radians(deg))])


def plan_take(gesture: str, subject: Subject, rng: np.random.Generator) -> Take:
    """Draw one performance: approach from a random edge, place, speed, direction."""
    edge = int(rng.integers(0, 4))  # the forearm comes from this image edge
    heading = (-90.0, 180.0, 90.0, 0.0)[edge] + float(rng.normal(0, 22))
    margin = 130.0 if gesture in ("wipe", "drag") else 105.0
    reach = 62.0 * PX_PER_MM * subject.size  # palm centre to the middle of the fingers
    middle = np.array([rng.uniform(margin, WIDTH - margin), rng.uniform(margin, HEIGHT - margin)])
    centre = tuple(float(v) for v in middle - reach * _unit(heading))
    lo, hi = SPEEDS.get(gesture, (0.0, 0.0))
    speed = float(rng.uniform(lo, hi)) * subject.speed
    if gesture == "drag":
        direction = float(rng.uniform(0, 360))
    elif gesture == "wipe":
        direction = float(rng.choice([-90.0, 90.0]) + rng.normal(0, 20))
    else:
        direction = float(rng.choice([-1.0, 1.0]))
    start = float(rng.uniform(0.05, 0.3))
    if direction < 0 and gesture in ("zoom", "spread_pile"):
        start = 1.0 - start
    return Take(gesture, centre, heading, speed, direction, start, tuple(rng.uniform(-1, 1, 8)))


def _tip_px(pose: Pose, subject: Subject, finger: int) -> np.ndarray:
    parts = [p for p in hand_parts(pose, subject) if p.ellipse is not None and p.z_mm == 0.0]
    # the contact pads come last, one per touching finger, in finger order
    touching = [i for i, f in enumerate(pose.fingers) if f.touch and not f.flat]
    pad = parts[len(parts) - len(touching) + touching.index(finger)]
    return np.array(pad.ellipse[0])


def take_poses(take: Take, subject: Subject, n: int, rng: np.random.Generator) -> list[Pose]:
    """The hand in each of ``n`` frames of ``take`` (with tremor from ``rng``)."""
    g, j, s = take.gesture, take.jitter, subject
    c0 = np.array(take.centre_px)
    k = PX_PER_MM * s.size
    poses = []
    for i in range(n):
        t = eased_s(i / FPS, take.ease_s)
        if g in STATIC:
            palm, fingers = static_pose(g, s, j)
            pose = Pose(tuple(c0), take.angle_deg, palm, fingers)
        elif g in ("drag", "wipe"):
            palm, fingers = static_pose("one_finger" if g == "drag" else "closed_hand", s, j)
            off = take.speed * t * PX_PER_MM * _unit(take.angle_deg + take.direction)
            pose = Pose(tuple(c0 + off), take.angle_deg + 4 * j[7] * t, palm, fingers)
        elif g == "zoom":
            p = float(np.clip(take.start + take.direction * take.speed * t, 0, 1))
            pose = Pose(tuple(c0), take.angle_deg, (20.0 + 3 * j[0]) * s.hover, pinch(p, j))
        elif g == "spread_pile":
            p = float(np.clip(take.start + take.direction * take.speed * t, 0, 1))
            palm = (24.0 + 3 * j[0]) * s.hover
            pose = Pose(tuple(c0), take.angle_deg, palm, five_tips(p, s, j))
        elif g == "rotate":
            fingers = pinch(0.75 + 0.1 * j[2], j)
            pose = Pose(tuple(c0), take.angle_deg, (22.0 + 3 * j[0]) * s.hover, fingers)
            thumb, index = _tip_px(pose, s, 0), _tip_px(pose, s, 1)
            pivot = thumb + take.pivot * (index - thumb)
            w = take.direction * take.speed * t
            pose = replace(
                pose,
                centre_px=tuple(_rotate_about(c0, pivot, w)),
                angle_deg=take.angle_deg + w,
            )
        else:
            raise ValueError(f"unknown gesture {g!r}")
        poses.append(tremble(pose, s, k, rng))
    return poses


def tremble(pose: Pose, s: Subject, k: float, rng: np.random.Generator) -> Pose:
    """Physiological tremor: a small shift, turn and finger wobble."""
    c = np.array(pose.centre_px) + rng.normal(0, s.tremor_mm * k, 2)
    fingers = tuple(
        replace(f, abduction=f.abduction + float(rng.normal(0, 0.5))) for f in pose.fingers
    )
    return Pose(tuple(c), pose.angle_deg + float(rng.normal(0, 0.25)), pose.palm_mm, fingers)


__all__ = ["DYNAMIC", "STATIC", "Take", "eased_s", "plan_take", "take_poses"]
