"""Rear-DI image formation for the camera twin (numpy + cv2).

Light model: the glass carries a diffuser lit from below by IR LEDs. Skin pressed on
the glass reflects strongly and sharply; skin above it reflects less and is blurred by
the diffuser, both growing with height (``contrast(h)``, ``blur_mm(h)``). The reflected
light is scaled by the LED illumination (hot spots, vignetting); the empty glass shows
its own glow with LED hot spots; the table frame outside the glass is dark. Then the
slow ambient drift (gain and offset), optional sudden illumination steps, and sensor
noise (read noise plus shot noise) give the 8-bit frame.

Pieces are grouped in height bands; each band is painted lowest-last (a lower piece
hides what is above it, seen from below), blurred once with the band's blur, and
composited over the bands above it.
"""

from __future__ import annotations

import functools
from collections.abc import Iterator
from dataclasses import dataclass, field

import cv2
import numpy as np

from .geometry import TableMapping
from .hand import Piece

#: Height bands (mm): [lo, hi). Pieces above the last edge are invisible.
BAND_EDGES_MM = (0.0, 0.5, 4.0, 9.0, 16.0, 28.0, 45.0, 75.0, 130.0)
CONTACT_LEVEL = 175.0  # grey levels added by touching skin at illumination 1
HOVER_LEVEL = 90.0  # skin just above the glass (an air gap), decaying with height
HOVER_DECAY_MM = 32.0


def contrast(h_mm: float) -> float:
    """Grey levels added by skin at height ``h_mm`` (illumination 1)."""
    if h_mm <= BAND_EDGES_MM[1]:
        return CONTACT_LEVEL
    return HOVER_LEVEL * float(np.exp(-h_mm / HOVER_DECAY_MM))


def blur_mm(h_mm: float) -> float:
    """Diffuser blur (Gaussian sigma, mm) of skin at height ``h_mm``."""
    return 0.5 + 0.6 * h_mm


@dataclass(frozen=True)
class Rig:
    """The camera set-up: mapping, LEDs, noise and drift. Seeded, hashable."""

    mapping: TableMapping = field(default_factory=TableMapping)
    seed: int = 0
    glow_level: float = 28.0  # empty-glass grey level
    hotspot_level: float = 60.0  # LED reflections in the empty glass
    n_hotspots: int = 6
    vignetting: float = 0.35  # illumination loss at the image corners
    noise_sigma: float = 1.8  # read noise, grey levels
    shot_gain: float = 0.04  # shot-noise variance per grey level
    drift_gain: float = 0.03  # slow ambient gain drift amplitude
    drift_offset: float = 3.0  # slow ambient offset drift amplitude (grey levels)
    drift_period_s: float = 40.0
    frame_level: float = 8.0  # the table frame seen outside the glass
    exposure_s: float = 0.0  # motion blur: shutter time over which moving hands smear
    illumination: float = 1.0  # LED power: scales the hands' light, the glow and hot spots


@functools.lru_cache(maxsize=8)
def rig_maps(rig: Rig) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """(illumination gain, empty-glass glow, glass mask) images, float32; cached per rig."""
    w, h = rig.mapping.image_px
    rng = np.random.default_rng(rig.seed)
    yy, xx = np.mgrid[0:h, 0:w].astype(np.float32)
    cx, cy = (w - 1) / 2, (h - 1) / 2
    r2 = ((xx - cx) ** 2 + (yy - cy) ** 2) / (cx**2 + cy**2)
    vig = 1.0 - rig.vignetting * r2
    # three LED rows (paper Fig. 1b): broad lobes along the top and across the middle
    lobes = np.zeros((h, w), np.float32)
    for row_y in (0.12, 0.5, 0.88):
        for _ in range(3):
            x0 = rng.uniform(0.1, 0.9) * w
            y0 = (row_y + rng.normal(0, 0.04)) * h
            s = rng.uniform(0.18, 0.3) * w
            lobes += np.exp(-((xx - x0) ** 2 + (yy - y0) ** 2) / (2 * s * s))
    lobes /= lobes.max()
    illum = vig * (0.8 + 0.3 * lobes)
    glow = rig.glow_level * illum
    # LED reflections in the glass: small spots along the LED rows, irregular strength
    for i in range(rig.n_hotspots):
        x0 = (i + 0.5) / rig.n_hotspots * w + rng.normal(0, 0.04 * w)
        y0 = (0.15 if i % 2 else 0.85) * h + rng.normal(0, 0.03 * h)
        s = rng.uniform(7, 14)
        glow += (
            rig.hotspot_level
            * rng.uniform(0.4, 1.0)
            * np.exp(-((xx - x0) ** 2 + (yy - y0) ** 2) / (2 * s * s))
        )
    mask = np.zeros((h, w), np.uint8)
    poly = np.round(rig.mapping.table_polygon_px() * 16).astype(np.int32)
    cv2.fillPoly(mask, [poly], 255, lineType=cv2.LINE_AA, shift=4)
    maskf = mask.astype(np.float32) / 255.0
    glow = glow * maskf + rig.frame_level * (1 - maskf)
    for a in (illum, glow, maskf):
        a.setflags(write=False)
    return illum.astype(np.float32), glow.astype(np.float32), maskf


def drift(rig: Rig, t_s: float) -> tuple[float, float]:
    """Slow ambient (gain, offset) at time ``t_s``: two incommensurate sinusoids."""
    ph = np.random.default_rng(rig.seed + 1).uniform(0, 2 * np.pi, 4)
    w1 = 2 * np.pi / rig.drift_period_s
    w2 = w1 * 3.7
    g = 1 + rig.drift_gain * (0.7 * np.sin(w1 * t_s + ph[0]) + 0.3 * np.sin(w2 * t_s + ph[1]))
    o = rig.drift_offset * (0.7 * np.sin(w1 * t_s + ph[2]) + 0.3 * np.sin(w2 * t_s + ph[3]))
    return float(g), float(o)


def _band_of(h_mm: float) -> int:
    for i in range(len(BAND_EDGES_MM) - 1):
        if h_mm < BAND_EDGES_MM[i + 1]:
            return i
    return -1


LOW_RES = 4  # bands blurrier than SHARP_SIGMA_PX are drawn and blurred at 1/4 resolution
SHARP_SIGMA_PX = 4.0


def _band_roi(polys: np.ndarray, pad: float, shape: tuple[int, int]) -> tuple[int, ...] | None:
    h, w = shape
    x0 = int(max(np.floor(polys[:, 0].min() - pad), 0))
    y0 = int(max(np.floor(polys[:, 1].min() - pad), 0))
    x1 = int(min(np.ceil(polys[:, 0].max() + pad) + 1, w))
    y1 = int(min(np.ceil(polys[:, 1].max() + pad) + 1, h))
    return (x0, y0, x1, y1) if x1 > x0 and y1 > y0 else None


def split_rows(a: np.ndarray, lens: list[int]) -> Iterator[np.ndarray]:
    """``a``'s rows in runs of ``lens`` (``np.split`` without its per-piece overhead)."""
    end = 0
    for n in lens:
        yield a[end : end + n]
        end += n


def _composite(out, mask, val, items, sigma_px, scale) -> None:
    """Paint one band's pieces (``items``: [outline, *holes] px, height, reflectance) at ``1/scale``
    resolution, blur, and composite over ``out`` (all three arrays at that resolution)."""
    contours = [c for cs, _, _ in items for c in cs]  # every piece's, converted at once
    lens = [len(c) for c in contours]
    flat = (np.vstack(contours) + 0.5) / scale - 0.5
    outline = np.repeat([i == 0 for cs, _, _ in items for i in range(len(cs))], lens)
    sigma = sigma_px / scale
    roi = _band_roi(flat[outline], 3 * sigma + 2, out.shape)
    if roi is None:
        return
    x0, y0, x1, y1 = roi
    m = mask[y0:y1, x0:x1]
    v = val[y0:y1, x0:x1]
    m[:] = 0
    v[:] = 0
    fixed = np.round((flat - np.array([x0, y0])) * 16).astype(np.int32)  # 1/16 px
    at = split_rows(fixed, lens)
    for cs, hp, refl in items:
        pts = [next(at) for _ in cs]  # outline, then holes
        if len(pts) > 1:  # a hole shows what lies above it: clear it first
            cv2.fillPoly(m, pts[1:], 0.0, lineType=cv2.LINE_AA, shift=4)
        cv2.fillPoly(m, pts, 1.0, lineType=cv2.LINE_AA, shift=4)
        cv2.fillPoly(v, pts, contrast(hp) * refl, lineType=cv2.LINE_8, shift=4)
    v *= m  # antialiased edges
    if sigma >= 0.6:
        cv2.GaussianBlur(m, (0, 0), sigma, dst=m)
        cv2.GaussianBlur(v, (0, 0), sigma, dst=v)
    o = out[y0:y1, x0:x1]
    o *= 1 - m
    o += v


#: bands blurred by at least this many pixels are smooth enough to be moved by an image
#: warp (``coherent``); sharper ones (the skin touching the glass) are drawn each frame
WARPABLE_SIGMA_PX = 1.0


def band_sigma_px(h_mm: float, px_per_mm: float) -> float | None:
    """The blur (Gaussian sigma, pixels) of skin at height ``h_mm`` as drawn: its band's
    (None: too high to be seen)."""
    b = _band_of(h_mm)
    if b < 0:
        return None
    return blur_mm(0.5 * (BAND_EDGES_MM[b] + BAND_EDGES_MM[b + 1])) * px_per_mm


def _bands(pieces: list[Piece], mapping: TableMapping) -> list[tuple[float, list]]:
    """The visible pieces by height band, highest first: (blur sigma px, items)."""
    visible = [(p, _band_of(p.h_mm)) for p in pieces]
    visible = [(p, b) for p, b in visible if b >= 0]
    if not visible:
        return []
    ppm = mapping.px_per_mm()
    contours = [c for p, _ in visible for c in (p.poly_mm, *p.holes)]
    sizes = [len(c) for c in contours]
    allpx = split_rows(mapping.mm_to_px(np.vstack(contours)), sizes)
    bands: dict[int, list[tuple[list[np.ndarray], float, float]]] = {}
    for p, b in visible:
        polys = [next(allpx) for _ in range(1 + len(p.holes))]
        bands.setdefault(b, []).append((polys, p.h_mm, p.refl))
    out = []
    for b in sorted(bands, reverse=True):  # highest band first, lower ones composite over
        items = sorted(bands[b], key=lambda it: -it[1])  # lower pieces paint last
        out.append((band_sigma_px(BAND_EDGES_MM[b], ppm), items))
    return out


def hand_layer(
    pieces: list[Piece], mapping: TableMapping, part: str = "all", over: np.ndarray | None = None
) -> np.ndarray:
    """Grey levels the hands add at illumination 1 (float32 image). ``part``: "all",
    "blurred" (the bands of ``WARPABLE_SIGMA_PX`` or more) or "sharp" (the others,
    composited over ``over``, the blurred part, in place): "sharp" over "blurred" is
    "all"."""
    w, h = mapping.image_px
    out = np.zeros((h, w), np.float32) if over is None else over
    bands = _bands(pieces, mapping)
    if part != "all":
        keep = (
            (lambda s: s >= WARPABLE_SIGMA_PX)
            if part == "blurred"
            else (lambda s: s < WARPABLE_SIGMA_PX)
        )
        bands = [(s, items) for s, items in bands if keep(s)]
    if not bands:
        return out
    lo_shape = (-(-h // LOW_RES), -(-w // LOW_RES))
    lo = None
    mask = np.empty((h, w), np.float32)
    val = np.empty((h, w), np.float32)
    for sigma, items in bands:
        if sigma > SHARP_SIGMA_PX:
            if lo is None:
                lo = np.zeros(lo_shape, np.float32)
                lo_mask, lo_val = np.empty_like(lo), np.empty_like(lo)
            _composite(lo, lo_mask, lo_val, items, sigma, LOW_RES)
            continue
        if lo is not None:  # the blurry bands are done: bring them to full resolution
            out[:] = cv2.resize(lo, (w, h), interpolation=cv2.INTER_LINEAR)
            lo = None
        _composite(out, mask, val, items, sigma, 1)
    if lo is not None:
        out[:] = cv2.resize(lo, (w, h), interpolation=cv2.INTER_LINEAR)
    return out


@functools.lru_cache(maxsize=2)
def _noise_bank(shape: tuple[int, int], seed: int) -> np.ndarray:
    """Standard-normal noise tiles; a frame takes a random crop (fast, seeded)."""
    rng = np.random.default_rng(seed + 7)
    bank = rng.standard_normal((4, shape[0] + NOISE_PAD, shape[1] + NOISE_PAD), np.float32)
    bank.setflags(write=False)
    return bank


NOISE_PAD = 64


def compose(
    layer: np.ndarray,
    rig: Rig,
    t_s: float,
    rng: np.random.Generator,
    *,
    step_gain: float = 1.0,
    step_offset: float = 0.0,
    noise: bool = True,
    light: float = 1.0,
) -> np.ndarray:
    """Illumination, glow, drift, steps and sensor noise -> uint8 frame; ``light`` is
    the sensor's exposure x gain (1: nominal), a multiplier before the 8-bit clip."""
    illum, glow, maskf = rig_maps(rig)
    g, o = drift(rig, t_s)
    img = layer * illum
    img *= maskf
    img += glow
    img *= g * step_gain * rig.illumination * light
    img += o + step_offset
    if noise:
        h, w = img.shape
        k, dy, dx = rng.integers(0, 4), rng.integers(0, NOISE_PAD), rng.integers(0, NOISE_PAD)
        n = _noise_bank((h, w), rig.seed)[k, dy : dy + h, dx : dx + w]
        sd = np.maximum(img, 0)
        sd *= rig.shot_gain
        sd += rig.noise_sigma**2
        np.sqrt(sd, out=sd)
        sd *= n
        img += sd
    img += 0.5
    np.clip(img, 0, 255, out=img)
    return img.astype(np.uint8)
