"""The "phalanx" renderer: an independent rear-DI hand renderer, written from scratch.

It shares no rendering code with the camera twin (``plugins/twin/camera``) and is
meant as a second instrument: a classifier trained on one renderer and tested on the
other shows how much it depends on one renderer's look.

Hand model (hand frame in mm: x towards the fingers, y towards the little finger of a
right hand; a left hand is the mirror image):

* each finger is a chain of three phalanges with joint angles (MCP, PIP, DIP flexion)
  and an abduction; every phalanx is drawn as one ellipse at its mean height; a touching
  fingertip adds a flattened contact pad at the glass;
* the palm is a rounded polygon with thenar/hypothenar pads, the forearm a tapered band
  rising away from the glass and leaving the image;
* hand size, finger widths and lengths, skin reflectance, hover height and tremor are
  drawn per subject.

Optics: every part's height above the glass sets its brightness (touching skin
brightest, ``exp(-z / HOVER_MM)`` above) and its defocus (a disc growing with height);
parts are composited by height layers, the lowest in front (the camera looks from
below). The LED light field has two broad horizontal lobes (the perpendicular LED
rows), an edge rim (the parallel top row) and cos^4 vignetting; ``light_scale``
multiplies it. Noise: shot (signal dependent) + read noise + row banding, then
8-bit quantisation with clipping at 255.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field

import cv2
import numpy as np

NAME = "phalanx"
WIDTH, HEIGHT = 640, 480
PX_PER_MM = 0.82  # the glass (743 x 447 mm) seen by a 640 x 480 camera
DARK_LEVEL = 6.0  # sensor black level (grey levels)
BG_LEVEL = 30.0  # the diffuser's own glow at full light
SKIN_PEAK = 185.0  # touching skin of reflectance 1 at full light (above the glow)
HOVER_GAIN = 0.42  # brightness of skin just above the glass, relative to touching
HOVER_MM = 16.0  # height at which hovering skin dims by 1/e
TOUCH_MM = 0.8  # parts lower than this touch the glass
BLUR_PER_MM = 0.25  # defocus disc radius in px per mm of height (at PX_PER_MM)
SHOT_GAIN = 0.18  # shot-noise variance per grey level of signal
#: height layers (mm); each is blurred with the disc of its representative height
LAYER_EDGES = (0.0, TOUCH_MM, 5.0, 12.0, 24.0, 40.0, 65.0, 100.0, 160.0, 1e9)
LAYER_Z = (0.0, 2.5, 8.0, 17.0, 31.0, 51.0, 80.0, 128.0, 220.0)

FINGERS = ("thumb", "index", "middle", "ring", "little")
#: finger base (MCP; thumb: CMC) in the hand frame, mm
BASES_MM = ((-20.0, -30.0), (44.0, -26.0), (47.0, -8.0), (44.0, 10.0), (37.0, 27.0))
#: phalanx lengths (proximal, middle, distal; thumb: metacarpal, proximal, distal), mm
LENGTHS_MM = (
    (38.0, 31.0, 26.0),
    (42.0, 25.0, 20.0),
    (46.0, 29.0, 21.0),
    (43.0, 27.0, 20.0),
    (34.0, 20.0, 18.0),
)
WIDTHS_MM = (21.0, 18.0, 18.0, 17.0, 15.0)  # at the proximal phalanx; tapers distally
TAPER = (1.0, 0.9, 0.82)
PALM_MM = (
    (-46.0, -28.0),
    (-22.0, -40.0),
    (18.0, -40.0),
    (47.0, -35.0),
    (52.0, -9.0),
    (49.0, 13.0),
    (42.0, 34.0),
    (8.0, 40.0),
    (-30.0, 35.0),
    (-48.0, 18.0),
    (-52.0, -4.0),
)
FOREARM_MM = 800.0  # long enough to leave the frame from anywhere
FOREARM_SLOPE = 0.27  # the forearm rises ~15 degrees from the wrist


@dataclass(frozen=True)
class Subject:
    """One person's hand and skin (drawn by ``draw_subject``)."""

    name: str
    hand: str  # "left" | "right"
    size: float = 1.0  # overall scale
    width: float = 1.0  # finger width scale
    lengths: tuple[float, ...] = (1.0,) * 5  # per-finger length scale
    reflectance: float = 0.9  # skin IR reflectance (0..1)
    hover: float = 1.0  # scales the heights of lifted parts
    tremor_mm: float = 0.5
    spread: float = 1.0  # how far this person spreads the fingers
    pad: float = 1.0  # contact pad size (pressure, skin softness)
    speed: float = 1.0  # how fast this person moves


@dataclass(frozen=True)
class Finger:
    """One finger's pose: abduction (deg, + towards the little finger), flexion of the
    three joints (deg), and whether the tip touches or the whole finger lies flat."""

    abduction: float = 0.0
    flex: tuple[float, float, float] = (0.0, 10.0, 5.0)
    touch: bool = False
    flat: bool = False


@dataclass(frozen=True)
class Pose:
    """The hand in one frame: palm centre (px), finger direction (image deg, x right,
    y down), palm height (mm, 0 = lying on the glass) and the five fingers."""

    centre_px: tuple[float, float]
    angle_deg: float
    palm_mm: float
    fingers: tuple[Finger, ...]


@dataclass(frozen=True)
class Optics:
    """One session's light and sensor: the light field (H, W, float32, max 1), read
    noise, banding strength and the glass smudges (added to the glow)."""

    light: np.ndarray = field(repr=False)
    read_noise: float = 1.5
    banding: float = 0.7
    smudge: np.ndarray = field(repr=False, default_factory=lambda: np.zeros((1, 1), np.float32))


def draw_subject(name: str, hand: str, rng: np.random.Generator) -> Subject:
    """A random subject: anatomy, skin and habits."""
    return Subject(
        name=name,
        hand=hand,
        size=float(rng.uniform(0.88, 1.12)),
        width=float(rng.uniform(0.88, 1.12)),
        lengths=tuple(float(v) for v in rng.uniform(0.94, 1.06, 5)),
        reflectance=float(rng.uniform(0.8, 1.0)),
        hover=float(rng.uniform(0.75, 1.35)),
        tremor_mm=float(rng.uniform(0.25, 0.8)),
        spread=float(rng.uniform(0.8, 1.2)),
        pad=float(rng.uniform(0.85, 1.15)),
        speed=float(rng.uniform(0.85, 1.15)),
    )


# ---------------------------------------------------------------- light and sensor


def light_field(rng: np.random.Generator, size: tuple[int, int] = (WIDTH, HEIGHT)) -> np.ndarray:
    """The LED illumination of the glass, max 1: two broad horizontal lobes, a rim at
    the edges and cos^4 vignetting, each perturbed by ``rng``."""
    w, h = size
    y, x = np.mgrid[0:h, 0:w].astype(np.float32)
    cx, cy = w / 2 + rng.normal(0, 12), h / 2 + rng.normal(0, 10)
    r2 = (x - cx) ** 2 + (y - cy) ** 2
    focal = 900.0 * rng.uniform(0.9, 1.1)
    vignette = 1.0 / (1.0 + r2 / focal**2) ** 2
    field_ = np.full((h, w), 0.55, np.float32)
    for frac in (0.34, 0.68):
        yc = frac * h + rng.normal(0, 12)
        spread = 85.0 * rng.uniform(0.85, 1.2)
        lobe = 1.0 / np.cosh((y - yc) / spread) ** 2
        along = 1.0 - 0.25 * ((x - w / 2) / (w / 2)) ** 2
        field_ += 0.3 * rng.uniform(0.85, 1.15) * lobe * along
    edge = np.minimum(np.minimum(x, w - 1 - x), np.minimum(y, h - 1 - y))
    field_ += 0.18 * rng.uniform(0.8, 1.2) * np.exp(-edge / 55.0)
    tilt = 1.0 + rng.normal(0, 0.05) * (x / w - 0.5) + rng.normal(0, 0.05) * (y / h - 0.5)
    out = field_ * vignette * tilt
    return (out / out.max()).astype(np.float32)


def smudges(rng: np.random.Generator, size: tuple[int, int] = (WIDTH, HEIGHT)) -> np.ndarray:
    """Faint fingerprints and dust on the glass (grey levels at full light)."""
    w, h = size
    img = np.zeros((h, w), np.float32)
    for _ in range(int(rng.integers(4, 10))):
        c = (int(rng.uniform(0, w)), int(rng.uniform(0, h)))
        ax = (int(rng.uniform(6, 30)), int(rng.uniform(4, 20)))
        cv2.ellipse(img, c, ax, float(rng.uniform(0, 180)), 0, 360, float(rng.uniform(1, 4)), -1)
    return cv2.GaussianBlur(img, (0, 0), 6.0)


def draw_optics(rng: np.random.Generator) -> Optics:
    """One session's light field, read noise, banding and glass smudges."""
    return Optics(
        light=light_field(rng),
        read_noise=float(rng.uniform(1.0, 2.2)),
        banding=float(rng.uniform(0.3, 1.0)),
        smudge=smudges(rng),
    )


def expose(
    radiance: np.ndarray, optics: Optics, light_scale: float, rng: np.random.Generator
) -> np.ndarray:
    """Sensor: light field x ``light_scale`` x (glow + skin radiance), shot and read
    noise, row banding, 8-bit with clipping at 255."""
    h, w = radiance.shape
    smudge = optics.smudge if optics.smudge.shape == radiance.shape else 0.0
    signal = optics.light * light_scale * (BG_LEVEL + smudge + radiance)
    noise = rng.standard_normal((h, w), dtype=np.float32)
    sigma = np.sqrt(SHOT_GAIN * signal + optics.read_noise**2)
    rows = rng.normal(0, optics.banding, (h, 1)).astype(np.float32)
    phase = rng.uniform(0, 2 * math.pi)
    hum = 0.5 * optics.banding * np.sin(np.arange(h, dtype=np.float32)[:, None] / 9.0 + phase)
    img = DARK_LEVEL + signal + sigma * noise + rows + hum
    return np.clip(np.rint(img), 0, 255).astype(np.uint8)


def background(optics: Optics, light_scale: float, rng: np.random.Generator) -> np.ndarray:
    """The empty table under this light."""
    return expose(np.zeros((HEIGHT, WIDTH), np.float32), optics, light_scale, rng)


# ---------------------------------------------------------------- hand geometry


@dataclass(frozen=True)
class Part:
    """One drawable piece: an ellipse (centre px, semi-axes px, angle deg) or a polygon
    (points px), at height ``z_mm`` above the glass."""

    z_mm: float
    ellipse: tuple[tuple[float, float], tuple[float, float], float] | None = None
    polygon: np.ndarray | None = None


def _frame(pose: Pose, subject: Subject) -> tuple[np.ndarray, np.ndarray, np.ndarray, float]:
    """(centre, forward, side unit vectors in px, px per mm) of the hand."""
    t = math.radians(pose.angle_deg)
    fwd = np.array([math.cos(t), math.sin(t)])
    side = np.array([-math.sin(t), math.cos(t)])
    if subject.hand == "left":
        side = -side
    return np.asarray(pose.centre_px, float), fwd, side, PX_PER_MM * subject.size


def _to_px(pts_mm: np.ndarray, frame: tuple) -> np.ndarray:
    c, fwd, side, k = frame
    pts_mm = np.atleast_2d(pts_mm)
    return c + k * (pts_mm[:, :1] * fwd + pts_mm[:, 1:2] * side)


def _rounded(poly: np.ndarray, passes: int = 2) -> np.ndarray:
    """Chaikin corner cutting: a rounded closed polygon."""
    for _ in range(passes):
        nxt = np.roll(poly, -1, axis=0)
        poly = np.concatenate([0.75 * poly + 0.25 * nxt, 0.25 * poly + 0.75 * nxt], axis=1)
        poly = poly.reshape(-1, 2)
    return poly


def _chain_heights(lengths: np.ndarray, flex: tuple[float, ...], phi: float, hb: float):
    """Horizontal steps and heights of the joints for an MCP pitch ``phi`` (deg, down +)."""
    pitch = np.radians(phi + np.cumsum([0.0, flex[1], flex[2]]))
    dx = lengths * np.cos(pitch)
    z = hb - np.concatenate([[0.0], np.cumsum(lengths * np.sin(pitch))])
    return dx, z


def finger_chain(
    finger: Finger, lengths: np.ndarray, base_h: float, floor_mm: float
) -> tuple[np.ndarray, np.ndarray]:
    """Joint positions along the finger (mm from the base, 4 values, may run back under
    the palm) and heights (mm). A touching finger's MCP pitch is solved so that the tip
    reaches the glass; a flat finger lies on it; a lifted one stays above ``floor_mm``."""
    if finger.flat:
        dx = lengths * np.cos(np.radians(np.cumsum([0.0, finger.flex[1], finger.flex[2]])))
        return np.concatenate([[0.0], np.cumsum(dx)]), np.array([0.7, 0.5, 0.2, 0.0])
    if finger.touch:
        lo, hi = -60.0, 88.0
        for _ in range(30):
            mid = 0.5 * (lo + hi)
            _, z = _chain_heights(lengths, finger.flex, mid, base_h)
            lo, hi = (mid, hi) if z[-1] > 0 else (lo, mid)
        dx, z = _chain_heights(lengths, finger.flex, 0.5 * (lo + hi), base_h)
        z = np.maximum(z, 0.0)
        z[-1] = 0.0
    else:
        dx, z = _chain_heights(lengths, finger.flex, finger.flex[0], base_h)
        z = np.maximum(z, floor_mm)
    return np.concatenate([[0.0], np.cumsum(dx)]), z


def finger_parts(i: int, finger: Finger, pose: Pose, subject: Subject, frame: tuple) -> list:
    """One ellipse per phalanx (and a contact pad at a touching tip)."""
    _, _, _, k = frame
    lengths = np.array(LENGTHS_MM[i]) * subject.lengths[i]
    flat_hand = pose.palm_mm < TOUCH_MM
    base_h = (0.0 if flat_hand else pose.palm_mm + 5.0) if i else pose.palm_mm + 2.0
    s_pos, z = finger_chain(finger, lengths, base_h, 14.0 * subject.hover)
    a = math.radians(finger.abduction)
    u = np.array([math.cos(a), math.sin(a)])
    base = np.array(BASES_MM[i])
    joints = _to_px(base + s_pos[:, None] * u, frame)
    parts = []
    for j in range(3):
        w = WIDTHS_MM[i] * TAPER[j] * subject.width * subject.size * PX_PER_MM
        p0, p1 = joints[j], joints[j + 1]
        d = p1 - p0
        half = 0.5 * float(np.hypot(*d)) + 0.3 * w
        ang = math.degrees(math.atan2(d[1], d[0])) if np.hypot(*d) > 0.5 else 0.0
        mid = 0.5 * (p0 + p1)
        zj = 0.5 * (z[j] + z[j + 1])
        if finger.flat and j == 2:
            zj = 0.0
        parts.append(Part(zj, ((mid[0], mid[1]), (half, 0.5 * w), ang)))
    if finger.touch and not finger.flat:
        tip, prev = joints[3], joints[2]
        d = tip - prev
        n = d / max(float(np.hypot(*d)), 1e-6)
        w3 = WIDTHS_MM[i] * TAPER[2] * subject.width * subject.size
        c = tip - n * k * 0.3 * lengths[2]
        ax = (k * 0.36 * lengths[2] * subject.pad, k * 0.34 * w3 * subject.pad)
        parts.append(Part(0.0, ((c[0], c[1]), ax, math.degrees(math.atan2(n[1], n[0])))))
    return parts


def palm_parts(pose: Pose, subject: Subject, frame: tuple) -> list:
    """The palm polygon, its thenar/hypothenar pads and the forearm band."""
    h = pose.palm_mm
    flat = h < TOUCH_MM
    poly = _to_px(_rounded(np.array(PALM_MM)), frame)
    parts = [Part(1.5 if flat else h, polygon=poly)]
    k = frame[3]
    pads = (((-28.0, -20.0), (24.0, 16.0), 0.8), ((-30.0, 22.0), (24.0, 13.0), 0.9))
    for (x, y), (ax, ay), lift in pads:
        c = _to_px(np.array([x, y]), frame)[0]
        ang = math.degrees(math.atan2(frame[1][1], frame[1][0]))
        parts.append(Part(0.0 if flat else h * lift, ((c[0], c[1]), (k * ax, k * ay), ang)))
    if flat:  # the knuckle pads press too
        c = _to_px(np.array([38.0, 0.0]), frame)[0]
        ang = math.degrees(math.atan2(frame[1][1], frame[1][0]))
        parts.append(Part(0.0, ((c[0], c[1]), (k * 10.0, k * 34.0), ang)))
    parts += forearm_parts(h, frame)
    return parts


def forearm_parts(palm_mm: float, frame: tuple, pieces: int = 24) -> list:
    """A tapered band from the wrist back along the hand axis, rising as it goes."""
    z0 = palm_mm + 10.0
    out = []
    for p in range(pieces):
        x0, x1 = -46.0 - FOREARM_MM * p / pieces, -46.0 - FOREARM_MM * (p + 1) / pieces
        w0, w1 = 30.0 + 0.02 * (-46.0 - x0), 30.0 + 0.02 * (-46.0 - x1)
        quad = np.array([[x0 + 4, -w0], [x0 + 4, w0], [x1, w1], [x1, -w1]])
        z = z0 + FOREARM_SLOPE * (-46.0 - 0.5 * (x0 + x1))
        out.append(Part(z, polygon=_to_px(quad, frame)))
    return out


def hand_parts(pose: Pose, subject: Subject) -> list[Part]:
    """Every drawable part of the hand in this pose."""
    frame = _frame(pose, subject)
    parts = palm_parts(pose, subject, frame)
    for i, f in enumerate(pose.fingers):
        parts += finger_parts(i, f, pose, subject, frame)
    return parts


# ---------------------------------------------------------------- rasterising


def skin_gain(z_mm: float) -> float:
    """Brightness of skin at height ``z_mm`` relative to skin touching the glass."""
    if z_mm < TOUCH_MM:
        return 1.0
    return HOVER_GAIN * math.exp(-z_mm / HOVER_MM)


def _disc(radius: float) -> np.ndarray:
    r = max(radius, 0.5)
    n = int(math.ceil(r))
    y, x = np.mgrid[-n : n + 1, -n : n + 1].astype(np.float32)
    k = np.clip(r + 0.5 - np.hypot(x, y), 0.0, 1.0)
    return k / k.sum()


def defocus(img: np.ndarray, radius_px: float) -> np.ndarray:
    """Blur by a uniform disc (the out-of-focus image of a point through the diffuser);
    large discs are applied at reduced resolution."""
    if radius_px <= 0.0:
        return cv2.GaussianBlur(img, (0, 0), 0.7)
    f = 1 if radius_px < 6 else (2 if radius_px < 14 else 4)
    if f == 1:
        return cv2.filter2D(img, -1, _disc(radius_px), borderType=cv2.BORDER_REPLICATE)
    h, w = img.shape
    small = cv2.resize(img, (w // f, h // f), interpolation=cv2.INTER_AREA)
    small = cv2.filter2D(small, -1, _disc(radius_px / f), borderType=cv2.BORDER_REPLICATE)
    return cv2.resize(small, (w, h), interpolation=cv2.INTER_LINEAR)


def _paint(value: np.ndarray, alpha: np.ndarray, part: Part, level: int) -> None:
    shift = 4  # sub-pixel precision of the OpenCV drawing calls
    s = float(1 << shift)
    if part.ellipse is not None:
        (cx, cy), (ax, ay), ang = part.ellipse
        c = (int(round(cx * s)), int(round(cy * s)))
        axes = (max(int(round(ax * s)), 1), max(int(round(ay * s)), 1))
        for img, v in ((value, level), (alpha, 255)):
            cv2.ellipse(img, c, axes, ang, 0, 360, v, -1, cv2.LINE_AA, shift)
    else:
        pts = np.round(part.polygon * s).astype(np.int32)
        for img, v in ((value, level), (alpha, 255)):
            cv2.fillPoly(img, [pts], v, cv2.LINE_AA, shift)


def layer_of(z_mm: float) -> int:
    """Index of the height layer that ``z_mm`` falls in."""
    for i in range(len(LAYER_Z)):
        if z_mm < LAYER_EDGES[i + 1]:
            return i
    return len(LAYER_Z) - 1


def radiance(parts: list[Part], reflectance: float, size=(WIDTH, HEIGHT)) -> np.ndarray:
    """Skin radiance (grey levels at full light, before the light field) of ``parts``:
    per height layer the parts are painted (lower ones last) and defocused, then the
    layers are composited from the highest to the lowest (the camera is below)."""
    w, h = size
    out = np.zeros((h, w), np.float32)
    layers: dict[int, list[Part]] = {}
    for p in parts:
        layers.setdefault(layer_of(p.z_mm), []).append(p)
    for li in sorted(layers, reverse=True):
        value = np.zeros((h, w), np.uint8)
        alpha = np.zeros((h, w), np.uint8)
        for p in sorted(layers[li], key=lambda q: -q.z_mm):
            _paint(value, alpha, p, int(round(255 * skin_gain(p.z_mm))))
        radius = BLUR_PER_MM * LAYER_Z[li] * PX_PER_MM / 0.82 if li else 0.0
        v = defocus(value.astype(np.float32) / 255.0, radius)
        a = defocus(alpha.astype(np.float32) / 255.0, radius)
        out = out * (1.0 - a) + v
    return out * (SKIN_PEAK * reflectance)


def render(
    poses: list[Pose],
    subject: Subject,
    optics: Optics,
    light_scale: float,
    rng: np.random.Generator,
) -> np.ndarray:
    """(n, 480, 640) uint8 frames, one per pose."""
    frames = [
        expose(radiance(hand_parts(p, subject), subject.reflectance), optics, light_scale, rng)
        for p in poses
    ]
    return np.stack(frames)


def touch_mask(pose: Pose, subject: Subject, size=(WIDTH, HEIGHT)) -> np.ndarray:
    """Where skin touches the glass in this pose (bool, H x W), for checks and truth."""
    w, h = size
    value = np.zeros((h, w), np.uint8)
    alpha = np.zeros((h, w), np.uint8)
    for p in hand_parts(pose, subject):
        if p.z_mm < TOUCH_MM:
            _paint(value, alpha, p, 255)
    return alpha > 127


__all__ = [
    "NAME",
    "Finger",
    "Optics",
    "Pose",
    "Subject",
    "background",
    "draw_optics",
    "draw_subject",
    "hand_parts",
    "render",
    "touch_mask",
]
