"""A hand's touching skin in millimetres: the parts of the hand at least half as bright
as its brightest block (skin on the glass; skin above it dims quickly with height), as
connected regions with their areas and centroids.

Measured relative to the hand's own light, so the regions keep their extent under
dimmer or brighter light; where touching skin clips at 255 it stays above half the
level and the plateau is kept whole. Lengths are in mm through ``px_per_mm`` (the
camera's calibration, or the frame seeing the whole glass: ``default_px_per_mm``).
"""

from __future__ import annotations

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


def default_px_per_mm(width_px: int, height_px: int) -> float:
    """Scale of a camera that sees the whole glass and little more (its tighter side)."""
    return min(width_px / GLASS_MM[0], height_px / GLASS_MM[1])


def touch_regions(diff: np.ndarray, body: np.ndarray, parts, px_per_mm: float) -> np.ndarray:
    """The touching skin of the hands (``body``: their mask, uint8 0/255; ``parts``:
    ``segmentation.Parts``; a fingertip whose finger rises out of the mask, a part of its
    own, counts too) in the difference image ``diff`` (uint8, grey levels above the
    background): pixels above ``TOUCH_SHARE`` of the brightest part's level (a hovering
    palm, however large, is not touching skin while a fingertip touches) as regions:
    (k, 3) area mm^2, x px, y px, largest first."""
    x0, y0, x1, y1 = parts.win
    cut = float(np.clip(np.floor(TOUCH_SHARE * parts.peak.max()), 1, 254))
    _, on = cv2.threshold(diff[y0:y1, x0:x1], cut, 255, cv2.THRESH_BINARY)
    on = cv2.bitwise_and(on, body[y0:y1, x0:x1])
    bx, by, bw, bh = cv2.boundingRect(on)  # the regions only: a small part of the hands
    if bw == 0:
        return np.zeros((0, 3))
    on = on[by : by + bh, bx : bx + bw]
    x0, y0 = x0 + bx, y0 + by
    _, _, stats, cents = cv2.connectedComponentsWithStats(on, connectivity=8)
    mm2 = 1.0 / (px_per_mm * px_per_mm)
    area = stats[1:, cv2.CC_STAT_AREA].astype(float) * mm2
    keep = np.flatnonzero(area >= MIN_REGION_MM2)
    keep = keep[np.argsort(-area[keep])]
    return np.column_stack([area[keep], cents[1:][keep] + (x0, y0)]).reshape(-1, 3)


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
