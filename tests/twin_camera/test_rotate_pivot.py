"""Two-fingertip motions on the twin in more than one style. A rotate turns about the subject's ``pivot``: the thumb's touch (0, the
paper's knob, where the thumb stays still), the index's (1), or a point between them
(both fingertips move, as a rotate with two fingertips about their middle). The twin
only turned about the thumb, so a model trained on it read "two fingertips moving" as a
zoom or spread and missed rotates on renderers that turn about the middle (twin ->
silhouette dynamic 0.74 at 5 frames). A zoom kept the hand still (the thumb sweeps,
the index moves a third as far); with ``zoom_still`` the hand follows so that the tips' middle
stays, both tips moving. Randomised sets draw both."""

from __future__ import annotations

from dataclasses import replace

import numpy as np

from plugins.gestures.augment import WIDE_RANGES, wide_condition, wide_subject
from plugins.twin.camera.gestures import plan_take, take_pose
from plugins.twin.camera.hand import hand_pieces, make_subject


def _touches(gesture: str, t_s: float = 0.1, **style: float) -> list[dict[str, np.ndarray]]:
    """Where the thumb and the index touch at 0 and ``t_s`` s of a take (mm)."""
    s = replace(make_subject("s1"), ease_s=0.0, **style)
    take = plan_take(gesture, s, np.random.default_rng(4), (600.0, 400.0), tremor=False)
    at = []
    for t in (0.0, t_s):
        geo = hand_pieces(s, take_pose(take, t))
        at.append({c["finger"]: np.array(c["pos_mm"]) for c in geo.contacts})
    return at


def _moves(pivot: float) -> dict[str, float]:
    """How far the thumb's and the index's touch move over 0.1 s of a rotate (mm)."""
    at = _touches("rotate", pivot=pivot)
    return {f: float(np.linalg.norm(at[1][f] - at[0][f])) for f in ("thumb", "index")}


def test_a_rotate_turns_about_the_subjects_pivot():
    knob, index, middle = _moves(0.0), _moves(1.0), _moves(0.5)
    assert knob["thumb"] < 0.5 < 5.0 < knob["index"], knob
    assert index["index"] < 0.5 < 5.0 < index["thumb"], index
    assert middle["thumb"] > 3.0 and middle["index"] > 3.0, middle
    assert abs(middle["thumb"] - middle["index"]) < 0.3 * max(middle.values()), middle


def test_a_zoom_keeps_its_tips_middle_as_still_as_the_subject_does():
    for still in (0.0, 1.0):
        a, b = _touches("zoom", zoom_still=still)
        thumb, index = (float(np.linalg.norm(b[f] - a[f])) for f in ("thumb", "index"))
        middle = float(np.linalg.norm((b["thumb"] + b["index"] - a["thumb"] - a["index"]) / 2))
        if still == 0.0:  # the hand stays: one tip sweeps, the middle moves with it
            assert max(thumb, index) > 2 * min(thumb, index) and middle > 5.0, (thumb, index)
        else:
            assert middle < 0.5 and min(thumb, index) > 5.0, (thumb, index, middle)


def test_randomised_sets_draw_the_styles_and_plain_subjects_keep_the_old_ones():
    plain = make_subject("s1")
    assert plain.pivot == 0.0 and plain.zoom_still == 0.0
    conds = [wide_condition(3, s, g, r) for s in range(3) for g in range(10) for r in range(3)]
    for key in ("pivot", "zoom_still"):
        drawn = [c["hand"][key] for c in conds]
        lo, hi = WIDE_RANGES[key]
        assert min(drawn) < lo + 0.15 and max(drawn) > hi - 0.15
        assert getattr(wide_subject(plain, conds[0]["hand"]), key) == conds[0]["hand"][key]
