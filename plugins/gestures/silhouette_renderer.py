"""A third gesture renderer with its own hand and rear-DI optics ("silhouette").

It shares no code with the twin camera or the phalanx renderer, so a model trained on
those can be checked on hands, light and noise it has not seen. The hand
(``silhouette_gestures``) is a height field of capsules and a superellipse palm in table
mm; this module images it as the table's IR camera would:

* camera: 640 x 480 px at 0.861 px/mm seen from under the glass, with a slight barrel
  distortion and keystone; the image is shown as from above (x right, y down);
* light: brightness of skin falls with its height h as 1 / (1 + (h / h0)^2), h0 drawn
  per table in 20-32 mm; skin in contact with the diffuser reflects 1 / 0.7 times more;
* the diffuser blurs skin at height h with sigma 0.45 + 0.2 h mm (five height layers
  blurred with cv2.GaussianBlur and blended);
* an uneven IR field: 2-4 LED hot spots on a falloff to the edges, times ``light_scale``;
  the diffuser's own glow; rim of the table outside the glass dark;
* sensor: shot noise with Poisson statistics (variance = mean, 6 electrons per grey
  level), drawn by its normal approximation to keep a frame under 20 ms (the dimmest glass
  pixel collects about 60 electrons at x0.7 light, where Poisson's skew is only 0.13),
  read noise, fixed-pattern pixel gain and offset, row noise per frame, a gamma, 8-bit
  clip (touching skin clips under strong light).
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from functools import lru_cache
from pathlib import Path

import numpy as np

from console.plugin_api import UserError

from .dataset import GESTURES, write_background, write_sample
from .silhouette_gestures import (
    FPS,
    GLASS_MM,
    Capsule,
    Palm,
    build_parts,
    make_subject,
    performance,
)

SIZE_PX = (640, 480)
PX_PER_MM = 0.861
#: heights (mm) of the blur layers
LAYER_H_MM = (0.0, 4.0, 12.0, 28.0, 60.0)
TOUCH_DN = 192.0  # touching skin at nominal light, before the field
E_PER_DN = 6.0  # electrons per grey level (shot noise)
LIGHT_RANGE = (0.2, 3.0)


@dataclass(frozen=True)
class Table:
    """The table's optics and sensor, drawn once per seed (shared by all samples)."""

    h0_mm: float
    barrel_k: float
    keystone: float
    field: np.ndarray  # (H, W) IR field relative to nominal (1 = nominal)
    glow_dn: np.ndarray  # (H, W) diffuser glow at nominal light
    gain_map: np.ndarray  # fixed-pattern pixel gain
    offset_dn: np.ndarray  # fixed-pattern offset
    x_mm: np.ndarray  # table mm seen by each pixel
    y_mm: np.ndarray
    read_dn: float
    row_dn: float
    gamma: float


def blur_sigma_px(h_mm: float) -> float:
    """Diffuser blur of skin at height ``h_mm`` (px)."""
    return (0.45 + 0.2 * h_mm) * PX_PER_MM


def falloff(h_mm: np.ndarray, h0_mm: float) -> np.ndarray:
    """Skin brightness relative to touching skin: contact boost, then 1 / (1 + (h/h0)^2)."""
    h = np.asarray(h_mm, np.float32)
    return 0.7 / (1.0 + (h / h0_mm) ** 2) + 0.3 * np.exp(-h / 0.3)


@lru_cache(maxsize=4)
def table(seed: int) -> Table:
    """The table of dataset ``seed`` (cached: a few MB)."""
    rng = np.random.default_rng([seed, 7001])
    w, h = SIZE_PX
    k, ks = float(rng.uniform(0.02, 0.05)), float(rng.uniform(-0.02, 0.02))
    yy, xx = np.mgrid[0:h, 0:w].astype(np.float32)
    cx, cy = (w - 1) / 2, (h - 1) / 2
    r2 = ((xx - cx) ** 2 + (yy - cy) ** 2) / (0.5 * math.hypot(w, h)) ** 2
    scale = (1 + k * r2) * (1 + ks * (yy - cy) / cy)
    x_mm = GLASS_MM[0] / 2 + (xx - cx) * scale / PX_PER_MM
    y_mm = GLASS_MM[1] / 2 + (yy - cy) * scale / PX_PER_MM
    on = (x_mm >= 0) & (x_mm <= GLASS_MM[0]) & (y_mm >= 0) & (y_mm <= GLASS_MM[1])
    ex = (x_mm / GLASS_MM[0] - 0.5) * 2
    ey = (y_mm / GLASS_MM[1] - 0.5) * 2
    base = 0.78 + 0.22 * (1 - 0.5 * ex**2) * (1 - 0.6 * ey**2)
    spots = np.zeros_like(base)
    for _ in range(int(rng.integers(2, 5))):
        sx, sy = rng.uniform(0.15, 0.85) * GLASS_MM[0], rng.uniform(0.2, 0.8) * GLASS_MM[1]
        s = rng.uniform(60, 130)
        spots += rng.uniform(0.12, 0.3) * np.exp(
            -((x_mm - sx) ** 2 + (y_mm - sy) ** 2) / (2 * s * s)
        )
    spots *= min(1.0, 0.35 / max(float(spots.max()), 1e-6))  # hot spots reach at most +35 %
    field = np.where(on, base + spots, 0.12 * base).astype(np.float32)
    glow = (rng.uniform(18, 30) * field + np.where(on, 0.0, -1.0)).clip(1.0).astype(np.float32)
    return Table(
        h0_mm=float(rng.uniform(20, 32)),
        barrel_k=k,
        keystone=ks,
        field=field,
        glow_dn=glow,
        gain_map=rng.normal(1.0, 0.012, (h, w)).astype(np.float32),
        offset_dn=rng.normal(0.0, 0.8, (h, w)).astype(np.float32),
        x_mm=x_mm,
        y_mm=y_mm,
        read_dn=float(rng.uniform(1.2, 2.5)),
        row_dn=float(rng.uniform(0.4, 1.0)),
        gamma=float(rng.uniform(0.92, 1.08)),
    )


def mm_to_px(tab: Table, x_mm, y_mm):
    """Pixel (col, row) seeing table point (x, y), scalars or arrays (the distortion
    inverted by fixed-point iteration, < 0.01 px)."""
    w, h = SIZE_PX
    cx, cy = (w - 1) / 2, (h - 1) / 2
    dx = (np.asarray(x_mm, float) - GLASS_MM[0] / 2) * PX_PER_MM
    dy = (np.asarray(y_mm, float) - GLASS_MM[1] / 2) * PX_PER_MM
    px, py = dx, dy
    for _ in range(8):
        r2 = (px * px + py * py) / (0.5 * math.hypot(w, h)) ** 2
        s = (1 + tab.barrel_k * r2) * (1 + tab.keystone * py / cy)
        px, py = dx / s, dy / s
    if px.ndim == 0:
        return cx + float(px), cy + float(py)
    return cx + px, cy + py


# ------------------------------------------------------------------- height field


def _part_box(part: Capsule | Palm) -> tuple[float, float, float, float]:
    if isinstance(part, Capsule):
        r = max(part.r0_mm, part.r1_mm)
        xs, ys = (part.p0[0], part.p1[0]), (part.p0[1], part.p1[1])
        return min(xs) - r, min(ys) - r, max(xs) + r, max(ys) + r
    r = max(part.a_mm, part.b_mm) * 1.05
    return part.centre[0] - r, part.centre[1] - r, part.centre[0] + r, part.centre[1] + r


def _capsule_h(c: Capsule, x: np.ndarray, y: np.ndarray) -> np.ndarray:
    dx, dy = c.p1[0] - c.p0[0], c.p1[1] - c.p0[1]
    t = ((x - c.p0[0]) * dx + (y - c.p0[1]) * dy) / max(dx * dx + dy * dy, 1e-9)
    t = np.clip(t, 0.0, 1.0)
    d2 = (x - c.p0[0] - t * dx) ** 2 + (y - c.p0[1] - t * dy) ** 2
    r = c.r0_mm + t * (c.r1_mm - c.r0_mm)
    hb = c.h0_mm + t * (c.h1_mm - c.h0_mm)
    under = r * r - d2
    h = hb + r - np.sqrt(np.maximum(under, 0.0)) - c.press_mm
    return np.where(under > 0, np.maximum(h, 0.0), np.inf)


def _palm_h(p: Palm, x: np.ndarray, y: np.ndarray) -> np.ndarray:
    ax, ay = p.axis
    rx, ry = x - p.centre[0], y - p.centre[1]
    v = rx * ax + ry * ay
    u = rx * ay - ry * ax
    rho = (np.abs(u / p.a_mm) ** p.n + np.abs(v / p.b_mm) ** p.n) ** (1.0 / p.n)
    ray = np.hypot(u, v) / np.maximum(rho, 1e-6)
    inset = np.clip((1.0 - rho) * ray, 0.0, p.edge_mm)
    edge = p.edge_mm - np.sqrt(p.edge_mm**2 - (p.edge_mm - inset) ** 2)
    hollow = p.hollow_mm * np.exp(
        -((u / (0.55 * p.a_mm)) ** 2) - ((v - 0.2 * p.b_mm) / (0.6 * p.b_mm)) ** 2
    )
    h = p.h_mm + p.tilt_mm * v / p.b_mm + hollow + edge - p.press_mm
    return np.where(rho < 1.0, np.maximum(h, 0.0), np.inf)


def height_field(
    tab: Table, parts: list, pad_px: int = 40
) -> tuple[np.ndarray, tuple[slice, slice]]:
    """Lowest skin (mm above the glass, inf where none) over the parts' region of the frame."""
    w, h = SIZE_PX
    mm = np.array([_part_box(part) for part in parts])  # (n, 4): x0 y0 x1 y1
    cols, rows = mm_to_px(tab, mm[:, [0, 0, 2, 2]], mm[:, [1, 3, 1, 3]])
    boxes = [
        (int(c.min()) - 2, int(r.min()) - 2, int(c.max()) + 3, int(r.max()) + 3)
        for c, r in zip(cols, rows, strict=True)
    ]
    c0 = max(min(b[0] for b in boxes) - pad_px, 0)
    r0 = max(min(b[1] for b in boxes) - pad_px, 0)
    c1 = min(max(b[2] for b in boxes) + pad_px, w)
    r1 = min(max(b[3] for b in boxes) + pad_px, h)
    roi = (slice(r0, max(r1, r0 + 1)), slice(c0, max(c1, c0 + 1)))
    hf = np.full((roi[0].stop - roi[0].start, roi[1].stop - roi[1].start), np.inf, np.float32)
    for part, (a0, b0, a1, b1) in zip(parts, boxes, strict=True):
        a0, b0, a1, b1 = max(a0, c0), max(b0, r0), min(a1, c1), min(b1, r1)
        if a1 <= a0 or b1 <= b0:
            continue
        x, y = tab.x_mm[b0:b1, a0:a1], tab.y_mm[b0:b1, a0:a1]
        hp = _capsule_h(part, x, y) if isinstance(part, Capsule) else _palm_h(part, x, y)
        sub = hf[b0 - r0 : b1 - r0, a0 - c0 : a1 - c0]
        np.minimum(sub, hp, out=sub)
    return hf, roi


def skin_image(tab: Table, hf: np.ndarray, reflect: float) -> np.ndarray:
    """Skin brightness (touching = ``reflect``) blurred by height in the diffuser: each
    height layer (hat-function weights) blurred with its own sigma, wide ones at half
    resolution."""
    import cv2  # lazy: OpenCV loads only when rendering

    skin = np.isfinite(hf)
    hs = np.where(skin, hf, 0.0).astype(np.float32)
    sig = np.where(skin, reflect * falloff(hs, tab.h0_mm), 0.0).astype(np.float32)
    out = np.zeros_like(sig)
    hs_lo, hs_hi = float(hs[skin].min(initial=0.0)), float(hs[skin].max(initial=0.0))
    for i, lev in enumerate(LAYER_H_MM):
        lo = LAYER_H_MM[i - 1] if i else -1.0
        hi = LAYER_H_MM[i + 1] if i + 1 < len(LAYER_H_MM) else 1e9
        if hs_hi <= lo or hs_lo >= hi:
            continue
        hat = np.interp(hs, (lo, lev, hi), (float(i == 0), 1.0, float(hi == 1e9)))
        layer = sig * hat.astype(np.float32)
        sigma = blur_sigma_px(lev)
        if sigma > 4.0 and min(layer.shape) > 16:
            small = cv2.resize(layer, None, fx=0.5, fy=0.5, interpolation=cv2.INTER_AREA)
            small = cv2.GaussianBlur(small, (0, 0), math.sqrt(sigma**2 - 0.25) / 2)
            out += cv2.resize(small, layer.shape[::-1], interpolation=cv2.INTER_LINEAR)
        else:
            out += cv2.GaussianBlur(layer, (0, 0), sigma)
    return out


def _sensor(
    tab: Table, signal_dn: np.ndarray, light_scale: float, rng: np.random.Generator
) -> np.ndarray:
    """8-bit frame of a mean signal (grey levels at nominal light), in place where it can."""
    import cv2  # lazy: OpenCV loads only when rendering

    mean = cv2.multiply(signal_dn, tab.gain_map, scale=float(light_scale))
    std = cv2.sqrt(cv2.add(mean, float(E_PER_DN * tab.read_dn**2)) * (1.0 / E_PER_DN))
    v = rng.standard_normal(mean.shape, dtype=np.float32)
    v *= std  # shot noise (variance = mean electrons) and read noise
    v += mean
    v += tab.offset_dn
    v += rng.normal(0, tab.row_dn, (mean.shape[0], 1)).astype(np.float32)
    v *= 16.0
    np.clip(v, 0, 4095, out=v)
    return _gamma_lut(round(tab.gamma, 4))[v.astype(np.uint16)]


@lru_cache(maxsize=8)
def _gamma_lut(gamma: float) -> np.ndarray:
    x = (np.arange(4096) + 0.5) / 16.0 / 255.0
    return np.clip(np.round(255.0 * x ** (1.0 / gamma)), 0, 255).astype(np.uint8)


def render_frame(
    tab: Table, parts: list, reflect: float, light_scale: float, rng: np.random.Generator
) -> np.ndarray:
    """One camera frame of a hand made of ``parts``."""
    hf, roi = height_field(tab, parts)
    skin = skin_image(tab, hf, reflect)
    sig = tab.glow_dn.copy()
    sig[roi] += TOUCH_DN * skin * tab.field[roi]
    return _sensor(tab, sig, light_scale, rng)


def render_background(tab: Table, light_scale: float, rng: np.random.Generator) -> np.ndarray:
    """The empty table."""
    return _sensor(tab, tab.glow_dn, light_scale, rng)


def render_sample(
    gesture: str, subject_index: int, rep: int, light_scale: float = 1.0, seed: int = 0
) -> tuple[list[np.ndarray], np.ndarray, dict]:
    """Frames, background and metadata of one performance, deterministic from
    (seed, subject, gesture, rep); the hand and its motion do not depend on the light."""
    if gesture not in GESTURES:
        raise UserError(f"gesture {gesture!r}: unknown; use one of {', '.join(GESTURES)}")
    for name, val in (("subject_index", subject_index), ("rep", rep), ("seed", seed)):
        if isinstance(val, bool) or not isinstance(val, (int, np.integer)) or val < 0:
            raise UserError(f"{name} {val!r}: must be a whole number, 0 or more")
    if isinstance(light_scale, bool) or not (
        isinstance(light_scale, (int, float)) and LIGHT_RANGE[0] <= light_scale <= LIGHT_RANGE[1]
    ):
        raise UserError(
            f"light_scale {light_scale!r}: must be a number from {LIGHT_RANGE[0]} to "
            f"{LIGHT_RANGE[1]} (1.0 is nominal light, e.g. 0.7 or 1.3)"
        )
    tab = table(int(seed))
    subject = make_subject(int(seed), int(subject_index))
    g = GESTURES.index(gesture)
    motion = np.random.default_rng([int(seed), int(subject_index), g, int(rep), 1])
    right = bool(motion.random() < 0.8) == subject.right_handed
    poses, truth = performance(gesture, subject, motion, right)
    noise = np.random.default_rng([int(seed), int(subject_index), g, int(rep), 2])
    frames, contacts = [], []
    for pose in poses:
        parts, tips = build_parts(subject, pose, right)
        frames.append(render_frame(tab, parts, subject.reflect, float(light_scale), noise))
        contacts.append({f: [round(v, 2) for v in xy] for f, xy in tips.items()})
    background = render_background(tab, float(light_scale), noise)
    truth.update(
        contacts_mm=contacts,
        palm_centre_mm=[[round(float(v), 2) for v in p.centre] for p in poses],
        angle_rad=[round(p.angle_rad, 5) for p in poses],
        hand_len_mm=round(subject.hand_len_mm, 1),
    )
    meta = {
        "subject": f"s{int(subject_index) + 1}",
        "gesture": gesture,
        "hand": "right" if right else "left",
        "fps": int(FPS),
        "renderer": "silhouette",
        "light_scale": float(light_scale),
        "seed": int(seed),
        "px_per_mm": PX_PER_MM,
        "truth": truth,
    }
    return frames, background, meta


def synth_silhouette(
    out: Path, subjects: int, reps: int, light_scale: float = 1.0, seed: int = 0
) -> int:
    """Write ``subjects`` x 10 gestures x ``reps`` samples in the dataset format; returns
    the number of samples written."""
    out = Path(out)
    for name, val in (("subjects", subjects), ("reps", reps)):
        if isinstance(val, bool) or not isinstance(val, int) or val < 1:
            raise UserError(f"{name} {val!r}: must be a whole number of at least 1")
    if out.exists() and not out.is_dir():
        raise UserError(f"{out}: exists and is not a folder; choose another --out")
    n = 0
    for s in range(subjects):
        for gesture in GESTURES:
            for rep in range(reps):
                frames, bg, meta = render_sample(gesture, s, rep, light_scale, seed)
                truth = meta.pop("truth")
                base = {k: meta.pop(k) for k in ("subject", "gesture", "hand", "fps")}
                write_sample(
                    out,
                    gesture,
                    f"{base['subject']}_{rep:03d}",
                    frames,
                    subject=base["subject"],
                    hand=base["hand"],
                    fps=base["fps"],
                    background=bg,
                    truth=truth,
                    extra=meta,
                )
                n += 1
    write_background(
        out,
        render_background(
            table(int(seed)), float(light_scale), np.random.default_rng([int(seed), 7002])
        ),
    )
    return n
