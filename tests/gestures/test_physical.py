"""Gesture features in physical units: against an analytic frame (known spacing and
areas in mm at two camera scales and three lights), and the same gesture seen by the
twin and the independent phalanx renderer."""

from __future__ import annotations

import math

import cv2
import numpy as np
import pytest

from plugins.gestures.features import frame_record, static_size
from plugins.gestures.physical import (
    MOTION_NAMES,
    STATIC_NAMES,
    TIP_MM2,
    physical_motion,
    physical_static,
    trend,
)
from plugins.gestures.renderer_sets import render_set
from plugins.gestures.vision import VisionParams, process_frame

COL = {n: i for i, n in enumerate(STATIC_NAMES)}


def _frame(ppm: float, light: float, tips_mm: list[tuple[float, float]], r_mm: float = 6.0):
    """A background and a frame: a dim hand (palm and forearm hovering) with bright
    round fingertips of radius ``r_mm`` at ``tips_mm`` (mm), seen at ``ppm`` px/mm."""
    rng = np.random.default_rng(0)
    bg = np.full((480, 640), 30.0)
    img = bg.copy()
    hand = np.zeros_like(bg, np.uint8)
    cx, cy = 320, 300
    cv2.ellipse(hand, (cx, cy), (int(45 * ppm), int(55 * ppm)), 0, 0, 360, 1, -1)
    cv2.rectangle(hand, (cx - int(30 * ppm), cy), (cx + int(30 * ppm), 479), 1, -1)
    img += 35.0 * light * cv2.GaussianBlur(hand.astype(float), (0, 0), 3)
    for x, y in tips_mm:
        tip = np.zeros_like(bg, np.uint8)
        px, py = cx + int(round(x * ppm)), cy - int(round(y * ppm))
        cv2.line(hand, (cx, cy), (px, py), 1, max(1, int(14 * ppm)))  # the finger
        cv2.circle(tip, (px, py), 0, 1, -1)
        d = cv2.distanceTransform(1 - tip, cv2.DIST_L2, 5) / ppm  # mm from the tip
        img += 180.0 * light * (d <= r_mm)
    img = img + 35.0 * light * (hand > 0) * (img < 30 + 35 * light * 0.9)
    noisy = img + rng.normal(0, 1.5, img.shape)
    bgn = bg + rng.normal(0, 1.5, bg.shape)
    as8 = lambda a: np.clip(a + 0.5, 0, 255).astype(np.uint8)  # noqa: E731
    return as8(noisy), as8(bgn)


@pytest.mark.parametrize("ppm", [0.82, 1.2])
def test_fingertip_spacing_and_area_are_millimetres_at_any_scale_and_light(ppm):
    """Two fingertips of radius 6 mm, 40 mm apart: the spacing is 40 mm within 5 % and
    each tip's area pi 6^2 = 113 mm^2 within 25 % (a disc's rim pixels), whatever the
    camera's scale (``px_per_mm``) and the light (x0.7 .. x1.3)."""
    tips = [(-20.0, 60.0), (20.0, 60.0)]
    for light in (0.7, 1.0, 1.3):
        img, bg = _frame(ppm, light, tips)
        res = process_frame(img, bg, VisionParams(px_per_mm=ppm))
        rec = frame_record(res)
        assert rec is not None, (ppm, light)
        v = physical_static(rec)
        assert v[COL["tips"]] == 2, (ppm, light, rec["regions_mm"])
        assert v[COL["top2_spacing_mm"]] == pytest.approx(40.0, rel=0.05), (ppm, light)
        areas = rec["regions_mm"][:2, 0]
        assert np.all(np.abs(areas / (math.pi * 36.0) - 1) < 0.25), (ppm, light, areas)
        assert TIP_MM2[0] < areas.min() and areas.max() < TIP_MM2[1]


def _rec(points_mm: np.ndarray) -> dict:
    regions = np.column_stack([np.full(len(points_mm), 120.0), points_mm])
    return {"touch_mm2": 120.0 * len(points_mm), "regions_mm": regions, "solidity": 0.5}


def test_motion_is_millimetres_at_60_fps_beyond_the_jitter_of_its_own_line():
    """A fingertip sliding 2 mm per frame at 60 fps moves 6 mm over 4 frames; the same
    slide filmed at 30 fps (4 mm per frame) is the same 6 mm at 60 fps. For white jitter
    of sigma per axis the least-squares line's change over frames 0..3 has variance
    (3 sigma)^2 / 5 per axis, and the standard error from the residuals estimates it
    without bias (both within 10 % over 1500 draws); a resting tip's jitter is mostly
    taken as jitter (median motion 0)."""
    slide60 = [_rec(np.array([[2.0 * i, 0.0]])) for i in range(4)]
    slide30 = [_rec(np.array([[4.0 * i, 0.0]])) for i in range(4)]
    assert physical_motion(slide60, 60.0)[2] == pytest.approx(6.0)
    assert physical_motion(slide30, 30.0)[2] == pytest.approx(6.0)
    rng = np.random.default_rng(3)
    sigma, f = 0.5, np.arange(4.0)
    var = (3 * sigma) ** 2 / 5
    draws = [trend(f, rng.normal(0, sigma, (4, 2)), 3) for _ in range(1500)]
    assert np.mean([c**2 for c, _ in draws]) == pytest.approx(var, rel=0.10)
    assert np.mean([se**2 for _, se in draws]) == pytest.approx(var, rel=0.10)
    still = [physical_motion([_rec(p[None]) for p in rng.normal(0, sigma, (4, 2))])[2]
             for _ in range(100)]  # fmt: skip
    assert np.median(still) == 0.0


def test_same_gesture_gives_the_same_millimetres_on_both_renderers():
    """The L's two fingertips' spacing (within 10 %) and a flat hand's touching area
    (within 20 %: measured 11-15 % apart, the renderers' hands differ), each renderer's
    median over its samples, agree under x0.7 and x1.3 light (in the hand's
    own scale, palm radii, the phalanx renderer's dim hovering palm made spacings 2-3
    times the twin's)."""
    g = ("l_shape", "closed_hand")
    cols = np.arange(static_size(16) - len(STATIC_NAMES), static_size(16))
    for light in (0.7, 1.3):
        med = {}
        for r in ("twin", "phalanx"):
            fs = render_set(r, 1, 2, light_scale=light, gestures=g, frames_list=(4,))
            x = fs.static[4][:, cols]
            med[r] = (
                np.median(x[fs.labels == "l_shape", COL["top2_spacing_mm"]]),
                np.median(np.expm1(x[fs.labels == "closed_hand", COL["touch_mm2_log"]])),
            )
        (sp_t, area_t), (sp_p, area_p) = med["twin"], med["phalanx"]
        assert sp_p == pytest.approx(sp_t, rel=0.10), (light, med)
        assert area_p == pytest.approx(area_t, rel=0.20), (light, med)


def test_static_and_dynamic_are_told_apart_by_millimetres_on_both_renderers():
    """Over 6 frames a resting fingertip (tremor) moves less than 3 mm beyond its
    jitter and a dragging one more than 6 mm (the twin's drags start from rest), on
    either renderer (the motion score is the touching regions'
    largest displacement, mm at 60 fps)."""
    for r in ("twin", "phalanx"):
        fs = render_set(r, 1, 2, gestures=("one_finger", "drag"), frames_list=(6,))
        score = fs.score[6]
        assert score[fs.labels == "one_finger"].max() < 3.0, (r, score)
        assert score[fs.labels == "drag"].min() > 6.0, (r, score)


def _flat(pads: list[tuple[float, float, float]], shift: tuple[float, float]) -> dict:
    """A flat hand's record: pads (area mm^2, x mm, y mm) moved by ``shift``."""
    reg = np.array([(a, x + shift[0], y + shift[1]) for a, x, y in pads], float)
    return {"touch_mm2": float(reg[:, 0].sum()), "regions_mm": reg, "solidity": 0.8}


#: a flat hand's pads: the palm and finger pads
PALM = (3300.0, 330.0, 270.0)
PADS = [(465.0, 332.0, 353.0), (235.0, 391.0, 349.0), (370.0, 417.0, 379.0),
        (475.0, 424.0, 330.0), (345.0, 425.0, 365.0)]  # fmt: skip


def test_a_resting_flat_hand_whose_pads_split_and_merge_does_not_move():
    """Under dim light a flat hand's pads split, merge and flicker from frame to frame
    (one pad into two 18 mm apart, a pad joining the palm): the skin's centroid jumps
    by millimetres, the hand does not move. A wipe moving every pad moves as far."""
    split = [(230.0, 374.0, 358.0), (350.0, 397.0, 388.0)]
    frames = [
        [PALM, (600.0, 388.0, 376.0), *PADS],
        [PALM, *split, *PADS],
        [PALM, (600.0, 388.0, 376.0), *PADS[1:]],
        [(3800.0, 334.0, 281.0), *split, *PADS[1:]],
        [PALM, *split, *PADS],
    ]
    rest = physical_motion([_flat(p, (0.0, 0.0)) for p in frames])
    assert rest[MOTION_NAMES.index("track_dmax_mm")] < 0.5
    wipe = physical_motion([_flat(p, (5.0 * i, 0.0)) for i, p in enumerate(frames)])
    assert wipe[MOTION_NAMES.index("track_dmax_mm")] == pytest.approx(20.0, abs=0.5)
