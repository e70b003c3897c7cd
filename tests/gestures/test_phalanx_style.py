"""The phalanx renderer's randomised motion style: slow starts and a rotate's pivot (a
model trained on phalanx takes that all started at full speed, turning about the
fingertips' midpoint, read the twin's slow starts as static and its thumb-pivot rotates
as zooms: phalanx -> twin dynamic 0.84 at 4 frames)."""

from __future__ import annotations

from dataclasses import replace

import numpy as np

from plugins.gestures.phalanx_gestures import _tip_px, eased_s, plan_take, take_poses
from plugins.gestures.phalanx_renderer import Subject
from plugins.gestures.renderer_sets import PHALANX_EASE_S, phalanx_style

SUBJECT = Subject("s1", "right", reflectance=0.95, tremor_mm=0.0)


def _take(gesture: str, **style):
    return replace(plan_take(gesture, SUBJECT, np.random.default_rng(3)), **style)


def _tips(take, n: int = 4) -> np.ndarray:
    poses = take_poses(take, SUBJECT, n, np.random.default_rng(0))
    return np.array([[_tip_px(p, SUBJECT, 0), _tip_px(p, SUBJECT, 1)] for p in poses])


def test_eased_start_moves_less_early_and_none_is_the_plain_take():
    assert eased_s(0.05, 0.0) == 0.05
    assert 0 < eased_s(1 / 60, 0.05) < 0.25 / 60  # the first step a quarter of full speed
    plain = take_poses(_take("drag"), SUBJECT, 4, np.random.default_rng(0))
    same = take_poses(_take("drag", ease_s=0.0), SUBJECT, 4, np.random.default_rng(0))
    assert [p.centre_px for p in plain] == [p.centre_px for p in same]
    slow = take_poses(_take("drag", ease_s=0.05), SUBJECT, 4, np.random.default_rng(0))
    moved = [np.hypot(*np.subtract(p[-1].centre_px, p[0].centre_px)) for p in (plain, slow)]
    assert moved[1] < 0.6 * moved[0]


def test_rotate_turns_about_the_chosen_pivot():
    about_thumb = _tips(_take("rotate", pivot=0.0), 6)
    thumb, index = np.linalg.norm(about_thumb[-1] - about_thumb[0], axis=1)
    assert thumb < 0.25 * index  # the thumb stays (but for the tremble), the index turns
    middle = _tips(_take("rotate"))
    moved = np.linalg.norm(middle[-1] - middle[0], axis=1)
    assert moved.min() > 0.5 * moved.max()  # the plain take: both tips move alike


def test_style_is_seeded_and_spans_its_ranges():
    styles = [phalanx_style(3, 0, 7, rep, 1.0) for rep in range(40)]
    assert styles == [phalanx_style(3, 0, 7, rep, 1.0) for rep in range(40)]
    pivots = [s["pivot"] for s in styles]
    assert min(pivots) < 0.15 and max(pivots) > 0.85
    assert phalanx_style(3, 0, 7, 0, 1.3)["ease_s"] == PHALANX_EASE_S * 1.3
