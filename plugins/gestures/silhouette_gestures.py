"""The silhouette renderer's hand: subjects, poses and the ten gestures as moving parts.

A hand is a palm (superellipse), a forearm and five fingers, each finger a chain of
tapered capsules. Every part carries the height of its underside above the glass (mm),
so the optics (``silhouette_renderer``) see touching skin at 0 mm and the rest rising
with the pose. Palm-local frame: origin at the palm centre, +v from the wrist to the
fingers, +u to the little finger of a right hand (a left hand mirrors u). Table frame:
mm from the glass corner, x along the long edge.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from plugins.gestures.dataset import GESTURES

GLASS_MM = (743.46, 447.29)
FPS = 60.0
N_FRAMES = 6
FINGERS = ("thumb", "index", "middle", "ring", "little")
#: finger length as a share of the hand length (thumb from its carpometacarpal joint); width (mm)
LENGTH_SHARE = {"thumb": 0.5, "index": 0.40, "middle": 0.43, "ring": 0.41, "little": 0.33}
WIDTH_MM = {"thumb": 19.0, "index": 17.0, "middle": 17.0, "ring": 16.0, "little": 14.5}
#: base of each finger in palm-local units of (half width a, half length b)
BASE_AB = {
    "thumb": (-0.75, -0.45),  # its carpometacarpal joint: the thenar hides the first part
    "index": (-0.62, 0.92),
    "middle": (-0.20, 0.97),
    "ring": (0.22, 0.93),
    "little": (0.60, 0.80),
}
#: how fast things move (per second), drawn uniformly
SPEED = {
    "drag_mm_s": (130.0, 450.0),
    "wipe_mm_s": (130.0, 450.0),
    "rotate_deg_s": (60.0, 250.0),
    "spacing_mm_s": (80.0, 300.0),
}


@dataclass(frozen=True)
class Capsule:
    """A tapered capsule from p0 to p1 (table mm) with end radii and underside heights;
    ``press_mm`` flattens the skin that touches the glass."""

    p0: tuple[float, float]
    p1: tuple[float, float]
    r0_mm: float
    r1_mm: float
    h0_mm: float
    h1_mm: float
    press_mm: float = 0.0


@dataclass(frozen=True)
class Palm:
    """A superellipse palm: centre, unit axis along +v, half sizes, exponent, heights."""

    centre: tuple[float, float]
    axis: tuple[float, float]
    a_mm: float
    b_mm: float
    n: float
    h_mm: float
    hollow_mm: float
    tilt_mm: float
    press_mm: float
    edge_mm: float = 12.0


@dataclass(frozen=True)
class Subject:
    """One person's anatomy (independent of the light)."""

    hand_len_mm: float
    palm_a_mm: float
    palm_b_mm: float
    palm_n: float
    length_mm: dict[str, float]
    width_mm: dict[str, float]
    patch_w_mm: dict[str, float]  # fingertip contact width wanted
    patch_l_mm: dict[str, float]  # fingertip contact length wanted
    hover_mm: float  # palm height when pointing
    hollow_mm: float
    reflect: float  # skin IR reflectance relative to nominal
    right_handed: bool


def make_subject(seed: int, index: int) -> Subject:
    """Subject ``index`` of a set drawn from ``seed``."""
    rng = np.random.default_rng([seed, index, 101])
    hand = float(rng.uniform(165.0, 205.0))
    prop = rng.uniform(0.94, 1.06, size=4)
    length = {f: LENGTH_SHARE[f] * hand * float(rng.uniform(0.95, 1.05)) for f in FINGERS}
    wscale = hand / 185.0 * float(rng.uniform(0.94, 1.06))
    width = {
        f: float(np.clip(WIDTH_MM[f] * wscale * rng.uniform(0.96, 1.04), 14, 20)) for f in FINGERS
    }
    patch_w, patch_l = {}, {}
    for f in FINGERS:
        r_tip = 0.43 * width[f]
        patch_w[f] = float(rng.uniform(9.5, min(14.0, 1.9 * r_tip)))
        patch_l[f] = float(rng.uniform(max(12.5, patch_w[f] + 1.0), 17.5))
    return Subject(
        hand_len_mm=hand,
        palm_a_mm=0.225 * hand * float(prop[0]),
        palm_b_mm=0.285 * hand * float(prop[1]),
        palm_n=float(rng.uniform(2.4, 3.0)),
        length_mm=length,
        width_mm=width,
        patch_w_mm=patch_w,
        patch_l_mm=patch_l,
        hover_mm=float(rng.uniform(26.0, 42.0)),
        hollow_mm=float(rng.uniform(3.0, 7.0)),
        reflect=float(rng.uniform(0.9, 1.08)),
        right_handed=bool(rng.random() < 0.8),
    )


def patch_geometry(subject: Subject, finger: str) -> tuple[float, float, float]:
    """(press_mm, width_mm, length_mm) of a touching fingertip: a circular section of
    radius r pressed by p touches over 2 sqrt(2 r p - p^2)."""
    r = 0.43 * subject.width_mm[finger]
    w = subject.patch_w_mm[finger]
    p = r - math.sqrt(r * r - (w / 2) ** 2)
    return p, w, subject.patch_l_mm[finger]


@dataclass(frozen=True)
class Pose:
    """Where the hand is (table mm, rad) and what each finger does in palm-local mm."""

    centre: tuple[float, float]
    angle_rad: float  # direction of +v in the table frame
    palm_h_mm: float
    palm_press_mm: float
    fingers: dict[str, tuple]  # ("touch", (u, v)) | ("flat", deg) | ("curl",) | ("tuck",)


def _rot(angle: float) -> np.ndarray:
    """Columns: table directions of +u and +v for +v at ``angle``."""
    c, s = math.cos(angle), math.sin(angle)
    return np.array([[s, c], [-c, s]])


def build_parts(subject: Subject, pose: Pose, right: bool) -> tuple[list, dict]:
    """The pose's parts in table mm, and the touching fingertips' centres (table mm)."""
    R = _rot(pose.angle_rad)
    mirror = 1.0 if right else -1.0
    c = np.asarray(pose.centre, float)

    def to_table(u: float, v: float) -> tuple[float, float]:
        p = c + R @ np.array([mirror * u, v])
        return float(p[0]), float(p[1])

    a, b, h = subject.palm_a_mm, subject.palm_b_mm, pose.palm_h_mm
    press = pose.palm_press_mm
    v_dir = R @ np.array([0.0, 1.0])
    parts: list = [
        Palm(
            to_table(0, 0),
            (float(v_dir[0]), float(v_dir[1])),
            a,
            b,
            subject.palm_n,
            h,
            subject.hollow_mm,
            3.0 if press else -4.0,
            press,
        ),
        Capsule(
            to_table(0, -0.85 * b), to_table(0, -0.85 * b - 160), 0.62 * a, 0.72 * a, h + 10, h + 70
        ),
    ]
    tips: dict[str, tuple[float, float]] = {}
    for f, spec in pose.fingers.items():
        bu, bv = BASE_AB[f]
        base = np.array([bu * a, bv * b])
        L, r = subject.length_mm[f], 0.5 * subject.width_mm[f]
        hk = h + (3.0 if f != "thumb" else -2.0)
        kind = spec[0]
        if kind == "touch":
            tip = np.asarray(spec[1], float)
            d = tip - base
            reach = float(np.hypot(*d))
            unit = d / max(reach, 1e-6)
            reach = float(np.clip(reach, 0.35 * L, 0.97 * L))
            tip = base + unit * reach
            p, w, lc = patch_geometry(subject, f)
            dist = min(0.24 * L, 0.45 * reach)
            dip = tip - unit * dist
            cap = math.sqrt(2 * 0.43 * 2 * r * p - p * p)
            h_dip = p * dist / max(lc - cap, 2.0)
            pip = base + unit * (0.5 * (reach - dist))
            pts, hs = [base, pip, dip, tip], [hk, 0.5 * (hk + h_dip) + 2.0, h_dip, 0.0]
            rs, pr = [r, 0.93 * r, 0.9 * r, 0.86 * r], p
            tips[f] = to_table(*tip)
        elif kind == "flat":
            ang = math.radians(spec[1])
            unit = np.array([math.sin(ang), math.cos(ang)])
            # pads under each phalanx touch, the joint creases between them do not
            pts = [base + unit * L * k for k in (0.0, 0.25, 0.49, 0.63, 0.77, 0.9, 1.0)]
            hs = [h + 5.0, 0.5, 3.3, 0.5, 3.0, 0.3, 1.0]
            rs = [r, 0.96 * r, 0.93 * r, 0.92 * r, 0.9 * r, 0.88 * r, 0.86 * r]
            pr = 3.0 if press else 0.0
        elif kind == "curl":
            unit = np.array([0.12 * bu, 1.0])
            unit /= np.hypot(*unit)
            knuck = base + unit * 0.42 * L * 0.5
            fold = knuck - unit * 0.15 * L
            low = max(hk - 0.45 * L * 0.8, 9.0)
            pts, hs, rs, pr = [base, knuck, fold], [hk, low, low + 5], [r, 0.95 * r, 0.9 * r], 0.0
        else:  # tuck: a thumb resting beside the curled fingers, hovering
            unit = np.array([0.35, 1.0]) / math.hypot(0.35, 1.0)
            pts = [base, base + unit * 0.4 * L, base + unit * 0.72 * L]
            hs, rs, pr = [hk, 0.6 * h + 4, 0.45 * h + 4], [r, 0.92 * r, 0.85 * r], 0.0
        for i in range(len(pts) - 1):
            parts.append(
                Capsule(
                    to_table(*pts[i]), to_table(*pts[i + 1]), rs[i], rs[i + 1], hs[i], hs[i + 1], pr
                )
            )
    return parts, tips


# --------------------------------------------------------------------------- gestures


def _pointing(fingers_touch: dict[str, tuple[float, float]]) -> dict[str, tuple]:
    out: dict[str, tuple] = {f: ("curl",) for f in FINGERS if f != "thumb"}
    out["thumb"] = ("tuck",)
    for f, tip in fingers_touch.items():
        out[f] = ("touch", tip)
    return out


def _flat(spread: bool, rng: np.random.Generator) -> dict[str, tuple]:
    if spread:
        degs = {"thumb": -62, "index": -17, "middle": -3, "ring": 10, "little": 24}
    else:
        degs = {"thumb": -24, "index": -4, "middle": 0, "ring": 3, "little": 7}
    return {f: ("flat", d + float(rng.uniform(-4, 4))) for f, d in degs.items()}


def _pinch(subject: Subject, spacing_mm: float, tilt_deg: float) -> dict[str, tuple]:
    """Thumb and index tips ``spacing_mm`` apart about a point in front of the palm."""
    q = np.array(pinch_centre(subject))
    ang = math.radians(tilt_deg)
    e = np.array([math.cos(ang), math.sin(ang)])  # thumb -> index
    return _pointing(
        {"thumb": tuple(q - e * spacing_mm / 2), "index": tuple(q + e * spacing_mm / 2)}
    )


def pinch_centre(subject: Subject) -> tuple[float, float]:
    """Palm-local point the thumb and index pinch about."""
    return (-0.85 * subject.palm_a_mm, subject.palm_b_mm + 0.3 * subject.length_mm["index"])


def performance(
    gesture: str, subject: Subject, rng: np.random.Generator, right: bool
) -> tuple[list[Pose], dict]:
    """The ``N_FRAMES`` poses of one performance and its ground truth."""
    if gesture not in GESTURES:
        raise ValueError(f"unknown gesture {gesture!r}")
    a, b, hl = subject.palm_a_mm, subject.palm_b_mm, subject.hand_len_mm
    margin = 0.55 * hl
    c0 = np.array(
        [rng.uniform(margin, GLASS_MM[0] - margin), rng.uniform(margin, GLASS_MM[1] - margin)]
    )
    phi0 = float(rng.uniform(0, 2 * math.pi))
    t = (np.arange(N_FRAMES) + float(rng.uniform(0, 3))) / FPS
    t = t - t[0]
    sign = float(rng.choice([-1.0, 1.0]))
    mirror = 1.0 if right else -1.0
    hover = subject.hover_mm * float(rng.uniform(0.9, 1.1))
    truth: dict = {"gesture": gesture, "hand": "right" if right else "left"}
    poses: list[Pose] = []
    if gesture in ("one_finger", "two_finger", "l_shape", "closed_hand", "open_hand"):
        if gesture == "one_finger":
            fingers = _pointing({"index": (-0.55 * a, b + 0.8 * subject.length_mm["index"])})
        elif gesture == "two_finger":
            gap = float(rng.uniform(8, 16))
            fingers = _pointing(
                {
                    "index": (-0.55 * a - gap / 2, b + 0.8 * subject.length_mm["index"]),
                    "middle": (-0.2 * a + gap / 2, b + 0.8 * subject.length_mm["middle"]),
                }
            )
        elif gesture == "l_shape":
            fingers = _pointing(
                {
                    "index": (-0.6 * a, b + 0.85 * subject.length_mm["index"]),
                    "thumb": (-0.8 * a - 0.55 * subject.length_mm["thumb"], 0.0),
                }
            )
        else:
            fingers = _flat(gesture == "open_hand", rng)
        flat = gesture in ("closed_hand", "open_hand")
        walk = np.cumsum(rng.normal(0, 0.18, size=(N_FRAMES, 2)), axis=0)
        walk -= walk[0]
        walk *= np.minimum(1.0, 0.6 / np.maximum(np.hypot(*walk.T), 1e-9))[:, None]
        wob = np.radians(
            np.clip(rng.normal(0, 0.08, size=N_FRAMES), -0.15, 0.15)
        )  # < 0.4 mm at a tip
        for k in range(N_FRAMES):
            poses.append(
                Pose(
                    tuple(c0 + walk[k]),
                    phi0 + wob[k],
                    0.0 if flat else hover,
                    1.8 if flat else 0.0,
                    fingers,
                )
            )
        truth["tremor_mm"] = float(np.hypot(*walk.T).max())
    elif gesture in ("drag", "wipe"):
        key = "drag_mm_s" if gesture == "drag" else "wipe_mm_s"
        speed = float(rng.uniform(*SPEED[key]))
        if gesture == "drag":
            fingers = _pointing({"index": (-0.55 * a, b + 0.8 * subject.length_mm["index"])})
            direc = float(rng.uniform(0, 2 * math.pi))
        else:
            fingers = _flat(False, rng)
            direc = (
                phi0 - (math.pi / 2 if sign > 0 else -math.pi / 2) + float(rng.uniform(-0.5, 0.5))
            )
        d = np.array([math.cos(direc), math.sin(direc)])
        flat = gesture == "wipe"
        for tk in t:
            poses.append(
                Pose(
                    tuple(c0 + d * speed * tk),
                    phi0,
                    0.0 if flat else hover,
                    1.6 if flat else 0.0,
                    fingers,
                )
            )
        truth.update(speed_mm_s=speed, direction_rad=direc)
    elif gesture in ("zoom", "rotate"):
        q_local = np.array(pinch_centre(subject))
        tilt = float(rng.uniform(20, 45))
        R0 = _rot(phi0)
        q = c0 + R0 @ (q_local * [mirror, 1.0])
        if gesture == "zoom":
            rate = float(rng.uniform(*SPEED["spacing_mm_s"])) * sign
            s0 = float(rng.uniform(25, 45) if sign > 0 else rng.uniform(75, 100))
            for tk in t:
                poses.append(
                    Pose(tuple(c0), phi0, hover, 0.0, _pinch(subject, s0 + rate * tk, tilt))
                )
            truth.update(spacing_rate_mm_s=rate, spacing0_mm=s0)
        else:
            omega = math.radians(float(rng.uniform(*SPEED["rotate_deg_s"]))) * sign
            s0 = float(rng.uniform(40, 70))
            fingers = _pinch(subject, s0, tilt)
            for tk in t:
                dphi = omega * tk
                Rd = np.array([[math.cos(dphi), -math.sin(dphi)], [math.sin(dphi), math.cos(dphi)]])
                poses.append(Pose(tuple(q + Rd @ (c0 - q)), phi0 + dphi, hover, 0.0, fingers))
            truth.update(omega_deg_s=math.degrees(omega), spacing_mm=s0)
        truth["pivot_mm"] = [float(q[0]), float(q[1])]
    else:  # spread_pile
        rate = float(rng.uniform(*SPEED["spacing_mm_s"])) * sign / 2  # radius rate
        r0 = float(rng.uniform(22, 32) if sign > 0 else rng.uniform(42, 55))
        centre = np.array([-0.15 * a, b + 0.2 * subject.length_mm["middle"]])
        beta = {"thumb": 215, "index": 125, "middle": 92, "ring": 62, "little": 35}
        for tk in t:
            rr = r0 + rate * tk
            tips = {
                f: tuple(
                    centre + rr * np.array([math.cos(math.radians(bd)), math.sin(math.radians(bd))])
                )
                for f, bd in beta.items()
            }
            poses.append(Pose(tuple(c0), phi0, 1.25 * hover, 0.0, _pointing(tips)))
        truth.update(spacing_rate_mm_s=2 * rate, radius0_mm=r0)
    return poses, truth
