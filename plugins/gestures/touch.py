"""A hand's touching skin in millimetres: connected regions with their areas and
centroids.

Touching skin is told from skin above the glass by two things every rear-DI image
shares, whatever its light falloff: it is the brightest skin around, and it is sharp
(the diffuser blurs skin by its height). Candidates are the pixels at least half as
bright as the hand's brightest block; of those, the core is what is at least
``CORE_SHARE`` as bright as the brightest skin within ``CORE_MM`` (a fingertip, not the
finger rising from it; each pad of a flat hand under its own light), and a core
touches when an edge on or next to it is steep (``SHARP_PER_MM`` of that level per mm),
or nearly as steep and as bright as the frame's sharpest core (a camera out of focus
softens every contact alike).
Curled fingers hovering a few mm up, 60-75 % as bright as a fingertip under a slow
falloff or clipping, are neither.

Measured relative to the hand's own light, so the regions keep their extent under
dimmer or brighter light; where touching skin clips at 255 it stays above the core's
level and the plateau is kept whole. Lengths are in mm through ``px_per_mm`` (the
camera's calibration, or the frame seeing the whole glass: ``default_px_per_mm``).
"""

from __future__ import annotations

import math

import cv2
import numpy as np

#: the glass the camera sees (mm, long edge x short edge)
GLASS_MM = (743.0, 447.0)
#: touching skin: at least this share of the hand's level above the background
TOUCH_SHARE = 0.5
#: regions smaller than this (mm^2) are noise, not skin on the glass
MIN_REGION_MM2 = 15.0
#: palms closer than this (mm) are pieces of one hand
SAME_HAND_MM = 200.0
#: regions kept per hand (largest first)
MAX_REGIONS = 8
#: the touching core: at least this share of the brightest skin within ``CORE_MM``
#: (skin just above the glass, however bright under a slow falloff or clipping, stays
#: below the contact's level next to it)
CORE_SHARE = 0.8
CORE_MM = 10.0
#: a core touches when an edge on or next to it rises at least this share of that
#: level per mm (touching skin: 0.22-0.45 on three renderers; curled fingers 9 mm
#: above the glass: 0.07-0.16)
SHARP_PER_MM = 0.19
#: ... or at least these shares of the sharpest core's edge and brightness among the
#: hands' cores (a camera out of focus or a blurring diffuser softens every contact's
#: edge alike: two fingertips touching in one frame differ by at most 1.3x in edge,
#: 0.16 against 0.21 on a twin defocused by 1 px, and by a few % in brightness; skin
#: above the glass beside a fingertip is 1.6-2.5x softer and 0.65-0.8 as bright); a
#: frame with one core keeps it
RELATIVE_SHARP = 0.55
RELATIVE_LEVEL = 0.85
#: a fingertip-sized region (up to this, mm^2) is placed from its far end from the
#: hand's palm along its own long axis: half its width back from that end, across it
#: where its pixels within ``END_MM`` of the end are (a round contact's centre). A
#: fingertip's contact
#: grows and shrinks toward the palm (a finger pressed flatter or lighter, the finger
#: just above the glass clipping under bright light) while its end stays: the
#: centroid of a resting fingertip stepped 3-5 mm when its contact grew by 40 %
END_MAX_MM2 = 1500.0
END_MM = 4.0
#: ... when that palm is at least this far from the region's centroid (mm): nearer, a
#: palm too dim to segment whole gives no direction
END_PALM_MM = 25.0


def default_px_per_mm(width_px: int, height_px: int) -> float:
    """Scale of a camera that sees the whole glass and little more (its tighter side)."""
    return min(width_px / GLASS_MM[0], height_px / GLASS_MM[1])


def touch_regions(
    diff: np.ndarray, body: np.ndarray, parts, px_per_mm: float, palms_px=None
) -> np.ndarray:
    """The touching skin of the hands (``body``: their mask in ``parts.win``, uint8 0/255; ``parts``:
    ``segmentation.Parts``; a fingertip whose finger rises out of the mask, a part of its
    own, counts too) in the difference image ``diff`` (uint8, grey levels above the
    background): pixels above ``TOUCH_SHARE`` of the brightest part's level (a
    hovering palm, however large, is not touching skin while a fingertip touches), their
    bright and sharp cores (see the module's docstring) as regions: (k, 3) area mm^2,
    x px, y px, largest first; with ``palms_px`` (the hands' palms, x y px) a
    fingertip-sized region's position is its far end from the nearest palm
    (``far_ends``), else its centroid."""
    x0, y0, x1, y1 = parts.win
    cut = min(max(math.floor(TOUCH_SHARE * float(parts.peak.max())), 1), 254)
    _, on = cv2.threshold(diff[y0:y1, x0:x1], cut, 255, cv2.THRESH_BINARY)
    on = cv2.bitwise_and(on, body)
    bx, by, bw, bh = cv2.boundingRect(on)  # the regions only: a small part of the hands
    if bw == 0:
        return np.zeros((0, 3))
    # a pixel more on each side: the edges' slope
    bx0, by0 = max(bx - 1, 0), max(by - 1, 0)
    on = on[by0 : by + bh + 1, bx0 : bx + bw + 1]
    sub = diff[y0 + by0 : y0 + by0 + on.shape[0], x0 + bx0 : x0 + bx0 + on.shape[1]]
    # the brightest skin within CORE_MM of each pixel, and the core: skin at least
    # CORE_SHARE of it
    k = 2 * max(round(CORE_MM * px_per_mm), 1) + 1
    near = cv2.dilate(sub, cv2.getStructuringElement(cv2.MORPH_RECT, (k, k)))
    core = cv2.compare(sub, cv2.convertScaleAbs(near, alpha=CORE_SHARE), cv2.CMP_GE)
    n, lab, stats, cents = cv2.connectedComponentsWithStats(cv2.bitwise_and(core, on), None, 8)
    if n < 2:
        return np.zeros((0, 3))
    # steep: an edge rising at least SHARP_PER_MM of that level per mm on or next to a
    # core, or RELATIVE_SHARP of the sharpest core's
    area = stats[:, cv2.CC_STAT_AREA] / (px_per_mm * px_per_mm)
    sharp = area >= MIN_REGION_MM2
    sharp[0] = False
    if np.count_nonzero(sharp) > 1:  # one core is kept, sharp or soft
        steep, level = core_sharpness(sub, near, lab, n, px_per_mm)
        best = np.flatnonzero(sharp)[np.argmax(steep[sharp])]
        soft = (steep >= RELATIVE_SHARP * steep[best]) & (level >= RELATIVE_LEVEL * level[best])
        sharp &= (steep >= SHARP_PER_MM) | soft
    keep = np.flatnonzero(sharp)
    keep = keep[np.argsort(-area[keep])]
    origin = np.array([x0 + bx0, y0 + by0], float)
    at = cents[keep] + origin
    if palms_px is not None and len(palms_px):
        at = far_ends(lab, stats, keep, at, area, origin, palms_px, px_per_mm)
    return np.column_stack([area[keep], at]).reshape(-1, 3)


def far_ends(lab, stats, keep, at, area, origin, palms_px, px_per_mm) -> np.ndarray:
    """``at`` ((k, 2) px, the regions ``keep`` of ``lab``) with each fingertip-sized
    region (``END_MAX_MM2``) placed from its far end along its long axis, the end away
    from the nearest palm (see ``END_MAX_MM2``)."""
    palms = np.asarray(palms_px, float).reshape(-1, 2)
    out = at.copy()
    for row, i in enumerate(keep):
        if area[i] > END_MAX_MM2:
            continue
        d = at[row] - palms
        j = int(np.argmin((d**2).sum(1)))
        dist = float(np.hypot(*d[j]))
        if dist < END_PALM_MM * px_per_mm:
            continue
        x, y, w, h = stats[i, :4]
        ys, xs = np.nonzero(lab[y : y + h, x : x + w] == i)
        rx = xs + (x + origin[0] - at[row, 0])  # pixels about the centroid
        ry = ys + (y + origin[1] - at[row, 1])
        # the region's own long axis (a fingertip and the finger just above the glass
        # beside it), pointing away from the palm
        t = 0.5 * math.atan2(2.0 * float(rx @ ry), float(rx @ rx - ry @ ry))
        u = np.array([math.cos(t), math.sin(t)])
        u = u if u @ d[j] >= 0 else -u
        v = np.array([-u[1], u[0]])
        along, across = rx * u[0] + ry * u[1], rx * v[0] + ry * v[1]
        end = along >= along.max() - END_MM * px_per_mm
        # the pad's centre: half the region's width back from its far end (a round
        # contact's centre), never behind its centroid (a contact wider than long)
        back = max(along.max() - 0.5 * (np.ptp(across) + 1.0), 0.0)
        out[row] = at[row] + back * u + float(across[end].mean()) * v
    return out


def core_sharpness(
    sub: np.ndarray, near: np.ndarray, lab: np.ndarray, n: int, px_per_mm: float
) -> tuple[np.ndarray, np.ndarray]:
    """Per labelled core of ``lab`` ((n,) each): the steepest edge on or next to it, as
    the share of the brightest skin near that edge (``near``) it rises per mm, and the
    core's brightest pixel in ``sub``."""
    dx, dy = cv2.spatialGradient(sub)  # |Sobel| is 8 x the grey levels per px
    rise = np.maximum(np.abs(dx), np.abs(dy)).astype(np.float32)
    ratio = cv2.dilate(rise * (px_per_mm / 8.0) / np.maximum(near, 1).astype(np.float32), None)
    inside = lab > 0
    idx = lab[inside]
    order = np.argsort(idx, kind="stable")  # per label: a sort and a reduce (ufunc.at is slow)
    idx = idx[order]
    starts = np.flatnonzero(np.r_[True, idx[1:] != idx[:-1]])
    best, level = np.zeros(n, np.float32), np.zeros(n, np.float32)
    best[idx[starts]] = np.maximum.reduceat(ratio[inside][order], starts)
    level[idx[starts]] = np.maximum.reduceat(sub[inside][order], starts)
    return best, level


def hand_touch(regions: np.ndarray, palms_px: list, index: int, same_px: float) -> dict:
    """The regions (``touch_regions``) of hand ``index``: those nearest to its palm of
    all the hands' palms (x, y px), or to a palm within ``same_px`` of its own (pieces
    of one hand that a dim finger split), at most ``MAX_REGIONS``: ``area_mm2``,
    ``regions`` and ``centroid_px`` (area-weighted; ``None`` without touching skin)."""
    if len(palms_px) > 1 and len(regions):
        palms = np.asarray(palms_px, float)
        d = np.linalg.norm(regions[:, None, 1:] - palms[None], axis=2)
        near = np.linalg.norm(palms - palms[index], axis=1) <= same_px
        regions = regions[near[d.argmin(axis=1)]]
    regions = regions[:MAX_REGIONS]
    total = float(regions[:, 0].sum())
    if total <= 0:
        return {"area_mm2": 0.0, "regions": np.zeros((0, 3)), "centroid_px": None}
    centroid = tuple(float(v) for v in (regions[:, 0] @ regions[:, 1:]) / total)
    return {"area_mm2": total, "regions": regions, "centroid_px": centroid}


class FrameTouch:
    """The touching skin of a frame's hands, found when first asked: only a gesture
    decision's first frames read it, so a frame loop does not pay for it on every frame.
    ``of(i)``: ``hand_touch`` of hand ``i`` (``palms_px`` in the hands' order)."""

    def __init__(
        self,
        diff: np.ndarray,
        body: np.ndarray,
        parts,
        px_per_mm: float,
        palms_px: list,
        same_px: float,
    ) -> None:
        self._inputs: tuple | None = (diff, body, parts, px_per_mm, palms_px)
        self._palms, self._same_px = list(palms_px), same_px
        self._regions: np.ndarray | None = None

    @property
    def regions(self) -> np.ndarray:
        """Every hand's touching regions (``touch_regions``)."""
        if self._regions is None:
            assert self._inputs is not None
            self._regions, self._inputs = touch_regions(*self._inputs), None
        return self._regions

    def of(self, index: int) -> dict:
        return hand_touch(self.regions, self._palms, index, self._same_px)
