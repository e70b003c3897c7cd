"""Simple rear-DI hand sketches drawn with OpenCV, for tests and benchmarks of the vision
pipeline (the IR camera twin is the realistic renderer; these are deliberately plain).

A hand is a palm ellipse, five finger bars, a forearm bar running off the image and
bright fingertip contacts; the body is dim and blurred, contacts bright and sharp. The
same ten gestures as the dataset (``STATIC``, ``DYNAMIC``) are scripted.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, replace

import cv2
import numpy as np

STATIC = ("one_finger", "two_finger", "l_shape", "closed_hand", "open_hand")
DYNAMIC = ("drag", "rotate", "spread_pile", "wipe", "zoom")

# finger order: thumb, index, middle, ring, little; (forward, side) base in mm, length mm
_BASES = ((-5.0, -36.0), (40.0, -27.0), (42.0, -9.0), (40.0, 9.0), (35.0, 26.0))
_LENGTHS = (55.0, 70.0, 78.0, 72.0, 58.0)
_WIDTHS = (20.0, 17.0, 17.0, 17.0, 16.0)
# pose -> per finger (extended, angle deg from forward, + = away from the thumb)
_POSES: dict[str, tuple[tuple[bool, float], ...]] = {
    "one_finger": ((False, -60), (True, 0), (False, 0), (False, 0), (False, 0)),
    "two_finger": ((False, -60), (True, -9), (True, 7), (False, 0), (False, 0)),
    "l_shape": ((True, -90), (True, 0), (False, 0), (False, 0), (False, 0)),
    "closed_hand": ((True, -25), (True, 2), (True, 0), (True, -2), (True, -4)),
    "open_hand": ((True, -75), (True, -22), (True, -6), (True, 10), (True, 26)),
}


@dataclass(frozen=True)
class HandPose:
    """One hand in one frame."""

    pos_px: tuple[float, float]  # palm centre
    theta_deg: float  # direction the fingers point, image angle (x right, y down)
    pose: str = "open_hand"
    left: bool = False
    px_per_mm: float = 0.86
    size: float = 1.0  # subject's hand size factor
    spread: float = 1.0  # multiplies the finger angles (spread/pile)
    thumb_deg: float | None = None  # override the thumb angle (zoom, rotate)
    flat: bool = False  # palm touching the glass too


def _dirs(theta_deg: float, left: bool) -> tuple[np.ndarray, np.ndarray]:
    t = math.radians(theta_deg)
    fwd = np.array([math.cos(t), math.sin(t)])
    side = np.array([-math.sin(t), math.cos(t)])
    return fwd, (-side if left else side)


def fingertips_px(h: HandPose) -> list[np.ndarray]:
    """Tips of the extended fingers in pixels."""
    return [tip for tip, ext in _fingers(h) if ext][:5]


def _fingers(h: HandPose):
    fwd, side = _dirs(h.theta_deg, h.left)
    k = h.px_per_mm * h.size
    c = np.asarray(h.pos_px, float)
    out = []
    for i, (ext, ang) in enumerate(_POSES[h.pose]):
        if i == 0 and h.thumb_deg is not None:
            ang = h.thumb_deg
        elif i > 0:
            ang = ang * h.spread
        base = c + k * (_BASES[i][0] * fwd + _BASES[i][1] * side)
        a = math.radians(ang)
        d = math.cos(a) * fwd + math.sin(a) * side
        length = _LENGTHS[i] if ext else 18.0
        out.append((base + k * length * d, ext))
    return out


def _draw_body(layer: np.ndarray, h: HandPose, value: int) -> None:
    fwd, side = _dirs(h.theta_deg, h.left)
    k = h.px_per_mm * h.size
    c = np.asarray(h.pos_px, float)
    ang = math.degrees(math.atan2(fwd[1], fwd[0]))
    cv2.ellipse(
        layer,
        (int(c[0]), int(c[1])),
        (int(47 * k), int(41 * k)),
        ang,
        0,
        360,
        value,
        -1,
        cv2.LINE_AA,
    )
    wrist = c - 45 * k * fwd
    far = c - 900 * k * fwd
    cv2.line(
        layer,
        tuple(int(v) for v in wrist),
        tuple(int(v) for v in far),
        int(value * 0.7),
        int(58 * k),
        cv2.LINE_AA,
    )
    for i, (tip, _) in enumerate(_fingers(h)):
        base = c + k * (_BASES[i][0] * fwd + _BASES[i][1] * side)
        cv2.line(
            layer,
            tuple(int(v) for v in base),
            tuple(int(v) for v in tip),
            value,
            max(int(_WIDTHS[i] * k), 2),
            cv2.LINE_AA,
        )


def background(shape: tuple[int, int] = (480, 640), level: float = 50.0) -> np.ndarray:
    """An empty-table IR image: vignetting and two LED hot spots (uint8)."""
    h, w = shape
    y, x = np.mgrid[0:h, 0:w].astype(np.float32)
    r2 = ((x - w / 2) / w) ** 2 + ((y - h / 2) / h) ** 2
    img = level * (1.0 - 0.8 * r2)
    for hx, hy in ((0.3, 0.4), (0.7, 0.6)):
        img += 25 * np.exp(-(((x - hx * w) / (0.12 * w)) ** 2 + ((y - hy * h) / (0.12 * h)) ** 2))
    return np.clip(img, 0, 255).astype(np.uint8)


def draw(
    hands: list[HandPose],
    bg: np.ndarray | None = None,
    *,
    noise: float = 2.0,
    body_level: int = 45,
    contact_level: int = 140,
    rng: np.random.Generator | None = None,
) -> np.ndarray:
    """One uint8 frame with ``hands`` over ``bg`` (default ``background()``)."""
    bg = background() if bg is None else bg
    rng = rng or np.random.default_rng(0)
    body = np.zeros(bg.shape, np.uint8)
    touch = np.zeros(bg.shape, np.uint8)
    for h in hands:
        _draw_body(body, h, body_level)
        k = h.px_per_mm * h.size
        for tip, ext in _fingers(h):
            if ext:
                cv2.circle(touch, (int(tip[0]), int(tip[1])), max(int(7 * k), 2), contact_level, -1)
        if h.flat:  # palm and extended fingers pressed on the glass
            c = np.asarray(h.pos_px)
            cv2.circle(touch, (int(c[0]), int(c[1])), int(30 * k), contact_level // 2, -1)
            fwd, side = _dirs(h.theta_deg, h.left)
            for i, (tip, ext) in enumerate(_fingers(h)):
                if ext:
                    base = c + k * (_BASES[i][0] * fwd + _BASES[i][1] * side)
                    cv2.line(
                        touch,
                        tuple(int(v) for v in base),
                        tuple(int(v) for v in tip),
                        contact_level // 2,
                        max(int(_WIDTHS[i] * k * 0.8), 2),
                    )
    body = cv2.GaussianBlur(body, (0, 0), 3.0)
    touch = cv2.GaussianBlur(touch, (0, 0), 1.0)
    img = bg.astype(np.float32) + body + touch
    if noise > 0:
        img += rng.normal(0, noise, img.shape).astype(np.float32)
    return np.clip(img, 0, 255).astype(np.uint8)


def gesture_poses(
    gesture: str,
    n_frames: int,
    *,
    pos_px: tuple[float, float] = (320, 220),
    theta_deg: float = -90.0,
    left: bool = False,
    size: float = 1.0,
    speed: float = 1.0,
) -> list[HandPose]:
    """The hand in each frame of a scripted gesture (static gestures stand still)."""
    base = HandPose(pos_px, theta_deg, "open_hand", left=left, size=size)
    out = []
    t = math.radians(theta_deg)
    fwd = np.array([math.cos(t), math.sin(t)])
    side = np.array([-math.sin(t), math.cos(t)])
    for i in range(n_frames):
        s = i * speed
        if gesture in STATIC:
            out.append(replace(base, pose=gesture, flat=gesture in ("closed_hand", "open_hand")))
        elif gesture == "drag":
            p = np.asarray(pos_px) + 9 * s * (0.6 * fwd + 0.8 * side)
            out.append(replace(base, pose="one_finger", pos_px=tuple(p)))
        elif gesture == "wipe":
            p = np.asarray(pos_px) + 12 * s * side
            out.append(replace(base, pose="closed_hand", pos_px=tuple(p), flat=True))
        elif gesture == "spread_pile":
            out.append(replace(base, pose="open_hand", spread=1.0 + 0.25 * s))
        elif gesture == "zoom":
            out.append(replace(base, pose="l_shape", thumb_deg=-40 - 12 * s))
        elif gesture == "rotate":
            h0 = replace(base, pose="l_shape", thumb_deg=-60.0)
            pivot = fingertips_px(h0)[0]
            a = math.radians(6 * s)
            d = np.asarray(pos_px) - pivot
            rot = np.array([[math.cos(a), -math.sin(a)], [math.sin(a), math.cos(a)]])
            p = pivot + rot @ d
            out.append(replace(h0, pos_px=tuple(p), theta_deg=theta_deg + 6 * s))
        else:
            raise ValueError(f"unknown gesture {gesture!r}")
    return out
