"""Parametric hands for the camera twin: subjects, poses, and the 3-D pieces they make.

A hand lives in its own frame (millimetres): origin at the wrist centre, ``+v`` towards
the fingers, ``+u`` to the little-finger side of a RIGHT hand seen from above (palm
down). A left hand is the mirror image (u -> -u). Heights are of the skin surface
facing the glass, in millimetres above it (0 = touching).

Fingers are planar kinematic chains: three phalanges with flexion angles from the
knuckle (MCP) which sits on the palm; a touching finger's first angle is solved so its
lowest point meets the glass, a lifted finger's so it clears the glass by its lift
height. ``hand_pieces`` turns a pose into flat pieces (polygon in table mm, height,
reflectance) for the renderer, plus the ground-truth contact points.
"""

from __future__ import annotations

import functools
import zlib
from dataclasses import dataclass, field, replace

import numpy as np

FINGERS: tuple[str, ...] = ("thumb", "index", "middle", "ring", "little")
PAD_MM = 2.0  # skin within this height of the glass is pressed flat on it (contact)
REST_MM = 4.0  # a curled finger this close to the glass rests on it (a knuckle contact)


@dataclass(frozen=True)
class Subject:
    """One person's hand and style; every number is drawn from the subject's seed."""

    name: str
    side: str  # dominant hand, "right" | "left"
    length_mm: float  # wrist crease to middle fingertip
    width_mm: float  # across the knuckles
    finger_len_mm: tuple[float, ...]  # thumb (from CMC) .. little (from MCP)
    finger_r_mm: tuple[float, ...]  # half-width of each finger at its base
    mcp_uv: tuple[tuple[float, float], ...]  # knuckle positions (right hand)
    rest_deg: tuple[float, ...]  # finger directions at rest, + towards little finger
    palm_uv: tuple[tuple[float, float], ...]  # palm outline (right hand)
    spread_deg: float  # how far this person spreads the fingers in open poses
    lift_mm: float  # how high curled fingers stay above the glass
    palm_lift_mm: float  # palm height in pointing poses
    speed: float  # gesture speed factor
    tremor_mm: float  # frame-to-frame jitter
    curvature: float  # typical path bend (1/mm)
    ease_s: float = 0.03  # how gently this person starts a motion (time constant)
    #: how far this person's piled fingertips converge on one point (0: each finger
    #: only closes in on its neighbours, tips ~20 mm apart; 1: the tips meet and touch)
    gather: float = 0.0
    #: where this person turns a rotate about: 0 the thumb's touch (the paper's knob), 1
    #: the index's; between them, both fingertips move (a rotate about their middle)
    pivot: float = 0.0
    #: how still a zoom's fingertips keep their middle (0: the hand stays and the thumb
    #: sweeps, the index a third as far; 1: the hand follows so both tips move, as much each way)
    zoom_still: float = 0.0
    #: added to each finger's direction in a closed hand (deg, thumb .. little; the
    #: thumb's + pressed in against the index, - standing off it: how tightly this
    #: person closes a flat hand)
    closed_turn_deg: tuple[float, ...] = (0.0, 0.0, 0.0, 0.0, 0.0)
    #: how far this person spreads an open flat hand's fingers (None: ``spread_deg``)
    open_spread: float | None = None

    @property
    def palm_len_mm(self) -> float:
        return self.length_mm - self.finger_len_mm[2]


def scaled_subject(subject: Subject, size: float = 1.0, hover: float = 1.0) -> Subject:
    """``subject`` with every length times ``size`` and the heights of lifted fingers and
    palm times ``hover`` (a condition of a recording session)."""
    if size == 1.0 and hover == 1.0:
        return subject
    return replace(
        subject,
        length_mm=subject.length_mm * size,
        width_mm=subject.width_mm * size,
        finger_len_mm=tuple(v * size for v in subject.finger_len_mm),
        finger_r_mm=tuple(v * size for v in subject.finger_r_mm),
        mcp_uv=tuple((u * size, v * size) for u, v in subject.mcp_uv),
        palm_uv=tuple((u * size, v * size) for u, v in subject.palm_uv),
        lift_mm=subject.lift_mm * hover,
        palm_lift_mm=subject.palm_lift_mm * hover,
    )


def subject_seed(name: str, seed: int = 0) -> int:
    return zlib.crc32(f"{name}/{seed}".encode())


def make_subject(name: str, seed: int = 0, side: str | None = None) -> Subject:
    """A subject with seeded size, proportions and style (paper: width 84.8 +- 5.2 mm)."""
    rng = np.random.default_rng(subject_seed(name, seed))
    length = float(np.clip(rng.normal(184.0, 9.0), 160, 210))
    width = float(np.clip(rng.normal(84.8, 5.2), 72, 98))
    mid = length * rng.uniform(0.43, 0.47)
    palm = length - mid
    ratios = np.array([1.18, 0.91, 1.0, 0.95, 0.76]) * rng.normal(1, 0.025, 5)
    flen = tuple(float(x) for x in mid * ratios)
    r = width / 85.0 * np.array([10.0, 8.6, 8.8, 8.3, 7.2]) * rng.normal(1, 0.04, 5)
    mcp_u = width * np.array([-0.36, -0.31, -0.10, 0.11, 0.30])
    mcp_v = palm * np.array([0.24, 0.97, 1.0, 0.97, 0.88])
    mcp = mcp_u + rng.normal(0, 1.0, 5), mcp_v + rng.normal(0, 1.5, 5)
    rest = np.array([-42.0, -7.0, 0.0, 6.0, 13.0]) + rng.normal(0, 2.0, 5)
    outline = np.array(
        [
            [-0.30, 0.0],
            [-0.47, 0.30],
            [-0.45, 0.72],
            [-0.36, 0.97],
            [-0.12, 1.02],
            [0.12, 1.00],
            [0.33, 0.92],
            [0.45, 0.70],
            [0.44, 0.30],
            [0.32, 0.0],
        ]
    ) * [width, palm] + rng.normal(0, 1.5, (10, 2))
    outline = _chaikin(outline)
    if side is None:
        side = "left" if rng.random() < 0.2 else "right"
    return Subject(
        name=name,
        side=side,
        length_mm=length,
        width_mm=width,
        finger_len_mm=flen,
        finger_r_mm=tuple(float(x) for x in r),
        mcp_uv=tuple(zip(map(float, mcp[0]), map(float, mcp[1]), strict=True)),
        rest_deg=tuple(float(x) for x in rest),
        palm_uv=tuple(tuple(map(float, p)) for p in outline),
        spread_deg=float(rng.uniform(0.8, 1.2)),
        lift_mm=float(rng.uniform(8, 18)),
        palm_lift_mm=float(rng.uniform(30, 50)),
        speed=float(rng.uniform(0.75, 1.3)),
        tremor_mm=float(rng.uniform(0.15, 0.5)),
        curvature=float(rng.uniform(-0.004, 0.004)),
        ease_s=float(rng.uniform(0.015, 0.05)),
    )


@dataclass(frozen=True)
class FingerPose:
    """Flexion (MCP, PIP, DIP) in degrees, abduction added to the rest direction
    (+ towards the little finger of a right hand), and contact or lift height."""

    flex_deg: tuple[float, float, float] = (0.0, 0.0, 0.0)
    abd_deg: float = 0.0
    contact: bool = False
    lift_mm: float = 10.0


@dataclass(frozen=True)
class HandPose:
    """Where a hand is and what it does. ``angle_deg``: direction of the fingers in the
    table frame (from +x towards +y)."""

    wrist_mm: tuple[float, float]
    angle_deg: float
    side: str = "right"
    palm_h_mm: tuple[float, float] = (0.0, 0.0)  # at the wrist, at the knuckles
    fingers: tuple[FingerPose, ...] = field(default_factory=lambda: (FingerPose(),) * 5)
    forearm_elev_deg: float = 18.0
    tip_radius_scale: float = 1.0  # < 1 shrinks the contact pads (fingertip-only case)

    def moved(self, d_mm: tuple[float, float] = (0, 0), d_deg: float = 0.0) -> HandPose:
        w = (self.wrist_mm[0] + d_mm[0], self.wrist_mm[1] + d_mm[1])
        return replace(self, wrist_mm=w, angle_deg=self.angle_deg + d_deg)


@dataclass
class Piece:
    """A flat piece of skin: polygon in table mm, height above the glass, reflectance."""

    poly_mm: np.ndarray
    h_mm: float
    refl: float = 1.0
    holes: tuple[np.ndarray, ...] = ()  # polygons cut out of this piece


_ARC = np.linspace(-np.pi / 2, np.pi / 2, 7)


def _chaikin(poly: np.ndarray, n: int = 2) -> np.ndarray:
    """Corner cutting of a closed polygon (rounds the palm outline)."""
    for _ in range(n):
        nxt = np.roll(poly, -1, axis=0)
        poly = np.stack([0.75 * poly + 0.25 * nxt, 0.25 * poly + 0.75 * nxt], 1).reshape(-1, 2)
    return poly


def _capsules(p0: np.ndarray, p1: np.ndarray, r0: np.ndarray, r1: np.ndarray) -> np.ndarray:
    """Outlines (K, 14, 2) of tapered capsules from ``p0`` (radius r0) to ``p1`` (r1)."""
    p0, p1 = np.atleast_2d(p0), np.atleast_2d(p1)
    r0, r1 = np.atleast_1d(r0)[:, None], np.atleast_1d(r1)[:, None]
    a = np.arctan2(p1[:, 1] - p0[:, 1], p1[:, 0] - p0[:, 0])[:, None]
    t1 = _ARC + a
    t0 = t1 + np.pi
    out = np.empty((len(p0), 14, 2))
    out[:, :7, 0] = p1[:, :1] + r1 * np.cos(t1)
    out[:, :7, 1] = p1[:, 1:] + r1 * np.sin(t1)
    out[:, 7:, 0] = p0[:, :1] + r0 * np.cos(t0)
    out[:, 7:, 1] = p0[:, 1:] + r0 * np.sin(t0)
    return out


def _capsule(p0: np.ndarray, p1: np.ndarray, r0: float, r1: float) -> np.ndarray:
    """Outline (14, 2) of one tapered capsule."""
    return _capsules(p0, p1, r0, r1)[0]


def _chains(z0: float, lens: np.ndarray, flex_rad: np.ndarray, n_sub: int) -> np.ndarray:
    """(K, n, 2) centreline ``(s, z)`` points of K flexion sets (K, 3), ``n_sub`` points
    per phalanx plus the base."""
    flex_rad = np.atleast_2d(flex_rad)
    phi = -np.cumsum(flex_rad, axis=1)  # (K, 3) direction of each phalanx
    phi = np.repeat(phi, n_sub, axis=1)  # (K, 3 n_sub)
    step = np.repeat(np.asarray(lens, dtype=float) / n_sub, n_sub)
    ds = np.cumsum(step * np.cos(phi), axis=1)
    dz = np.cumsum(step * np.sin(phi), axis=1)
    k = flex_rad.shape[0]
    s = np.concatenate([np.zeros((k, 1)), ds], axis=1)
    z = np.concatenate([np.full((k, 1), z0), z0 + dz], axis=1)
    return np.stack([s, z], axis=2)


def _radii(r_base: float, n: int) -> np.ndarray:
    return r_base * np.linspace(1.0, 0.82, n)


def _solve_mcp(z0, lens, flex, radii, target_mm, n_sub, theta_max, contact):
    """MCP flexion (rad) in [-45 deg, theta_max] putting the lowest skin point at the
    target: the smallest flexion that reaches the glass when touching, the largest
    that keeps the lift height when lifted. Unreachable: the closest approach."""
    lo, hi = np.radians(-45.0), np.radians(theta_max)
    th = np.linspace(lo, hi, 64)
    for _ in range(3):  # scan, then refine twice inside the bracket
        f = np.column_stack([th, np.full_like(th, flex[1]), np.full_like(th, flex[2])])
        low = (_chains(z0, lens, f, n_sub)[:, 1:, 1] - radii[1:]).min(axis=1)  # past the MCP
        ok = low <= target_mm if contact else low >= target_mm
        if contact:
            if not ok.any():
                return float(th[np.argmin(low)])
            i = int(np.argmax(ok))  # first reaching
            if i == 0:
                return float(th[0])
            th = np.linspace(th[i - 1], th[i], 16)
        else:
            if ok[-1]:
                return float(th[-1])
            if not ok.any():
                return float(th[np.argmax(low)])
            i = int(len(ok) - 1 - np.argmax(ok[::-1]))  # last keeping clear
            th = np.linspace(th[i], th[i + 1], 16)
    return float(th[-1] if contact else th[0])


@functools.lru_cache(maxsize=4096)
def finger_profile(
    pose: FingerPose,
    length_mm: float,
    r_mm: float,
    z_base_mm: float,
    *,
    thumb: bool = False,
    n_sub: int = 3,
) -> tuple[np.ndarray, np.ndarray]:
    """Centreline ``(s, z)`` points and radii of one finger; lowest skin = z - r.
    Cached (a held pose is solved once); the arrays are read-only."""
    parts = np.array([0.42, 0.31, 0.27] if thumb else [0.45, 0.30, 0.25]) * length_mm
    flex = np.radians(np.asarray(pose.flex_deg, dtype=float))
    n = 3 * n_sub + 1
    radii = _radii(r_mm, n)
    z0 = z_base_mm + r_mm
    if pose.contact:
        target = -0.5  # pressed a little: the pad flattens on the glass
        theta_max = 110.0
    else:
        target = max(pose.lift_mm, 0.5)
        theta_max = float(pose.flex_deg[0])
    flex[0] = _solve_mcp(z0, parts, flex, radii, target, n_sub, theta_max, pose.contact)
    sz = _chains(z0, parts, flex, n_sub)[0]
    sz.setflags(write=False)
    radii.setflags(write=False)
    return sz, radii


def _palm_height(v: np.ndarray, palm_len: float, h: tuple[float, float]) -> np.ndarray:
    t = np.clip(v / max(palm_len, 1e-6), 0, 1)
    return h[0] + (h[1] - h[0]) * t


def _clip_strip(poly: np.ndarray, v0: float, v1: float) -> np.ndarray:
    """Sutherland-Hodgman clip of a polygon (u, v) to v0 <= v <= v1."""

    def clip(pts, keep, inter):
        out = []
        n = len(pts)
        for i in range(n):
            a, b = pts[i], pts[(i + 1) % n]
            ka, kb = keep(a), keep(b)
            if ka:
                out.append(a)
            if ka != kb:
                out.append(inter(a, b))
        return out

    def at(v):
        return lambda a, b: a + (b - a) * ((v - a[1]) / (b[1] - a[1]))

    pts = list(poly)
    pts = clip(pts, lambda p: p[1] >= v0, at(v0)) if pts else pts
    pts = clip(pts, lambda p: p[1] <= v1, at(v1)) if pts else pts
    return np.asarray(pts, dtype=float).reshape(-1, 2)


@functools.lru_cache(maxsize=256)
def _palm_strips(palm_uv: tuple, n_strip: int) -> tuple[tuple[float, float, np.ndarray], ...]:
    """The palm outline cut in ``n_strip`` strips along v: (v0, v1, outline); a subject's
    own, cached (the arrays are read-only)."""
    palm = np.asarray(palm_uv, dtype=float)
    edges = np.linspace(palm[:, 1].min() - 1, palm[:, 1].max() + 1, n_strip + 1)
    out = []
    for v0, v1 in zip(edges[:-1], edges[1:], strict=True):
        strip = _clip_strip(palm, v0, v1)
        strip.setflags(write=False)
        out.append((v0, v1, strip))
    return tuple(out)


@dataclass
class HandGeometry:
    pieces: list[Piece]
    contacts: list[dict]  # {"finger", "kind": "tip"|"knuckle", "pos_mm"} touching the glass
    palm_contact: bool
    center_mm: tuple[float, float]
    tips_mm: dict[str, tuple[float, float, float]]  # finger -> (x, y, lowest height)


def hand_pieces(subject: Subject, pose: HandPose) -> HandGeometry:
    """Flatten a posed hand into pieces (table mm) plus ground-truth contacts."""
    mirror = -1.0 if pose.side == "left" else 1.0
    a = np.radians(pose.angle_deg)
    fwd = np.array([np.cos(a), np.sin(a)])  # +v in table mm
    # +u (little-finger side of a right hand, seen from above) is clockwise of +v
    right = np.array([np.sin(a), -np.cos(a)]) * mirror
    wrist = np.asarray(pose.wrist_mm, dtype=float)

    def to_table(uv: np.ndarray) -> np.ndarray:
        uv = np.asarray(uv, dtype=float).reshape(-1, 2)
        return wrist + uv[:, :1] * right + uv[:, 1:2] * fwd

    pieces: list[Piece] = []
    palm_len = subject.palm_len_mm
    h_w, h_m = pose.palm_h_mm

    # forearm: a tapering capsule from the wrist back to the table edge, rising
    n_arm = 6
    seg = 45.0
    elev = np.tan(np.radians(pose.forearm_elev_deg))
    ends = [[0.0, -i * seg + 12.0] for i in range(n_arm + 1)]  # wrist end first
    r0 = np.array([subject.width_mm * (0.36 + 0.02 * i) for i in range(n_arm)])
    xy = to_table(ends)
    for i, poly in enumerate(_capsules(xy[:-1], xy[1:], r0, r0 + 1.5)):
        v0, v1 = ends[i][1], ends[i + 1][1]
        h = h_w + 6.0 + elev * (-(v0 + v1) / 2)
        pieces.append(Piece(poly, max(h, 0.0), 0.85))

    # palm: strips along v with the interpolated height
    palm = np.asarray(subject.palm_uv, dtype=float)
    n_strip = 1 if abs(h_w - h_m) < 0.5 else 4
    for v0, v1, strip in _palm_strips(subject.palm_uv, n_strip):
        if len(strip) >= 3:
            h = float(_palm_height(np.array([(v0 + v1) / 2]), palm_len, (h_w, h_m))[0])
            h = 0.0 if h <= PAD_MM else h
            pieces.append(Piece(to_table(strip), h, 1.0))
    palm_contact = min(h_w, h_m) <= PAD_MM

    contacts: list[dict] = []
    tips: dict[str, tuple[float, float, float]] = {}
    for k, name in enumerate(FINGERS):
        fp = pose.fingers[k]
        base_uv = np.array(subject.mcp_uv[k])
        z_base = float(_palm_height(np.array([base_uv[1]]), palm_len, (h_w, h_m))[0])
        if k == 0:
            z_base = max(z_base - 2.0, 0.0)
        r = subject.finger_r_mm[k]
        sz, radii = finger_profile(fp, subject.finger_len_mm[k], r, z_base, thumb=k == 0)
        ang = np.radians(subject.rest_deg[k] + fp.abd_deg)
        d_uv = np.array([np.sin(ang), np.cos(ang)])
        uv = base_uv + sz[:, :1] * d_uv
        xy = to_table(uv)
        low = sz[:, 1] - radii
        seg_h = np.minimum(low[:-1], low[1:])
        touch = seg_h <= (PAD_MM if fp.contact else REST_MM)
        touching = [int(i) for i in np.flatnonzero(touch)]
        outlines = _capsules(xy[:-1], xy[1:], radii[:-1], radii[1:])
        if touching:
            rs = pose.tip_radius_scale * 0.62
            pads = _capsules(
                xy[:-1][touch], xy[1:][touch], radii[:-1][touch] * rs, radii[1:][touch] * rs
            )
            pieces += [Piece(pad, 0.0, 1.0) for pad in pads]
            # the rest of the finger's width curves away (fingertip-only: stays high)
            seg_h = np.where(
                touch, 60.0 if pose.tip_radius_scale < 1.0 else np.maximum(seg_h, 0.0) + 3.0, seg_h
            )
        pieces += [Piece(o, float(max(h, 0.0))) for o, h in zip(outlines, seg_h, strict=True)]
        tip = xy[-1]
        tips[name] = (float(tip[0]), float(tip[1]), float(max(low.min(), 0.0)))
        if fp.contact and touching:
            distal = [i for i in touching if i >= len(xy) - 1 - 3] or touching[-1:]
            pts = np.vstack([xy[i] for i in distal] + [xy[i + 1] for i in distal])
            contacts.append(
                {"finger": name, "kind": "tip", "pos_mm": tuple(map(float, pts.mean(axis=0)))}
            )
        elif touching:  # a curled finger resting on the glass: a real contact too
            pts = np.vstack([xy[i] for i in touching] + [xy[i + 1] for i in touching])
            contacts.append(
                {"finger": name, "kind": "knuckle", "pos_mm": tuple(map(float, pts.mean(axis=0)))}
            )

    # a hovering piece never hides a touching one: draw order is decided by the renderer
    center = to_table(palm.mean(axis=0, keepdims=True))[0]
    return HandGeometry(pieces, contacts, palm_contact, (float(center[0]), float(center[1])), tips)
