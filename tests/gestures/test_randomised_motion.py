"""Domain randomisation reaches the training samples' motion: a randomised twin set's
resting fingertips tremble up to a real hand's tremor and its gestures move up to x1.8
as far over their frames (a model trained on the twin read the phalanx renderer's
trembling fingertip, 2.3-2.8 mm beyond the fit's jitter, as a drag: its randomised
resting fingers had stayed under 1.24 mm), and the vision sees it."""

from __future__ import annotations

import numpy as np
import pytest

import plugins.gestures.augment as augment
from plugins.gestures.features import N_HARMONICS_MAX, sample_records
from plugins.gestures.physical import tips_mm
from plugins.gestures.renderer_sets import _twin_samples
from plugins.gestures.vision import VisionParams


@pytest.fixture
def people(monkeypatch) -> list:
    """The twin's people as each randomised sample changed them (``wide_subject``)."""
    seen: list = []
    real = augment.wide_subject

    def spy(subject, hand):
        seen.append(real(subject, hand))
        return seen[-1]

    monkeypatch.setattr(augment, "wide_subject", spy)
    return seen


def _seen(randomise: bool) -> dict[str, np.ndarray]:
    """Per gesture, each sample's index fingertip as the vision finds it over 4 frames:
    its RMS step (one_finger) or its travel (drag), mm at 60 fps (samples where it finds
    one fingertip in at least 3 frames)."""
    params = VisionParams(n_harmonics=N_HARMONICS_MAX)
    out: dict[str, list] = {"one_finger": [], "drag": []}
    for _, gesture, frames, bg, fps in _twin_samples(2, 6, 5, 1.0, randomise, tuple(out)):
        recs = [r for r in sample_records(frames[:4], bg, params) if r is not None]
        tips = np.array([t[0] for t in map(tips_mm, recs) if len(t) == 1]) * 60 / fps
        if len(tips) < 3:
            continue
        if gesture == "one_finger":
            out[gesture].append(np.sqrt((np.diff(tips, axis=0) ** 2).sum(axis=1).mean()))
        else:
            out[gesture].append(np.linalg.norm(tips[-1] - tips[0]))
    assert all(len(v) >= 10 for v in out.values())  # of 12
    return {g: np.array(v) for g, v in out.items()}


def test_randomised_twin_set_trembles_and_moves_over_wider_ranges(people):
    plain = _seen(False)
    assert not people
    wide = _seen(True)
    assert len(people) == 24
    assert max(p.tremor_mm for p in people) > 1.8  # up to a real hand's tremor
    assert max(p.speed for p in people) > 1.7
    # the vision sees it: resting fingertips that tremble and drags that go further
    assert wide["one_finger"].max() > 2 * plain["one_finger"].max()
    assert wide["drag"].max() > 2 * plain["drag"].max()


def test_wide_ranges_reach_a_real_hands_tremor_and_quick_gestures():
    assert augment.WIDE_RANGES["tremor_mm"][1] >= 2.0
    assert augment.WIDE_RANGES["speed"][1] >= 1.8
    hands = [augment.wide_condition(5, 0, g, rep)["hand"] for g in range(10) for rep in range(20)]
    assert max(h["tremor_mm"] for h in hands) > 1.8 and max(h["speed"] for h in hands) > 1.7
