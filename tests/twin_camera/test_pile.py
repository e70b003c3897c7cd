"""A pile of fingers on the twin: piled, the fingertips close in on each other, and as
far as the subject's ``gather`` says on one point until they touch (real piles bring the
tips together; the twin's stayed about 20 mm apart, so a pile whose fingertips merged
into fewer regions was never seen in training). Randomised sets draw ``gather``."""

from __future__ import annotations

from dataclasses import replace

import numpy as np

from plugins.gestures.augment import WIDE_RANGES, wide_condition, wide_subject
from plugins.twin.camera.gestures import _five_fingers
from plugins.twin.camera.hand import HandPose, hand_pieces, make_subject


def _tips(subject, p: float) -> np.ndarray:
    pose = HandPose((300.0, 200.0), 90.0, "right", palm_h_mm=(20.0, 15.0),
                    fingers=_five_fingers(subject, p, (0.0,) * 8))  # fmt: skip
    return np.array([c["pos_mm"] for c in hand_pieces(subject, pose).contacts])


def _nearest_and_span(tips: np.ndarray) -> tuple[float, float]:
    d = np.sqrt(((tips[:, None] - tips[None]) ** 2).sum(-1))
    return float((d + 1e9 * np.eye(len(d))).min()), float(d.max())


def test_a_gathering_subjects_piled_fingertips_meet():
    for name in ("s1", "s2", "s3"):
        s = make_subject(name)
        near0, span0 = _nearest_and_span(_tips(s, 0.1))
        near1, span1 = _nearest_and_span(_tips(replace(s, gather=1.0), 0.1))
        assert near0 > 20.0  # the old pile: tips a finger's width apart
        assert near1 < 14.0 and span1 < 0.75 * span0, (name, near1, span1, span0)
        # spread open, gathering changes nothing
        open0 = _tips(s, 1.0)
        assert np.allclose(open0, _tips(replace(s, gather=1.0), 1.0))


def test_randomised_sets_draw_how_far_piles_gather():
    conds = [wide_condition(3, s, g, r) for s in range(3) for g in range(10) for r in range(3)]
    gathers = [c["hand"]["gather"] for c in conds]
    lo, hi = WIDE_RANGES["gather"]
    assert min(gathers) < lo + 0.15 and max(gathers) > hi - 0.15
    s = wide_subject(make_subject("s1"), conds[0]["hand"])
    assert s.gather == conds[0]["hand"]["gather"]
