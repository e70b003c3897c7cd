"""What another renderer's hands show that the twin's do not, and the features that hold
across them: a fingertip seen in two pieces is one fingertip; a region flickering into
one frame of a held pose is none; a resting hand's fingers that tremble each their own
way do not move it; a zoom is a zoom at any speed (a model trained on slow zooms read
another renderer's fast ones as rotates); a pointing hand under dim light is found."""

from __future__ import annotations

import numpy as np

from plugins.gestures.features import (
    N_GRID,
    N_HARMONICS_MAX,
    N_MOTION,
    desc_size,
    select_dynamic,
    select_static,
    static_features,
    static_size,
)
from plugins.gestures.physical import (
    COUNT_INDEX,
    MOTION_NAMES,
    SHARE_PARTS,
    STATIC_NAMES,
    TREMOR_MM,
    motion_shares,
    physical_motion,
    tips_mm,
)


def _rec(tips: list[tuple[float, float]], area: float = 120.0) -> dict:
    """A frame record of a hand above the glass touching it with ``tips`` (mm)."""
    reg = np.array([[area, x, y] for x, y in tips]).reshape(-1, 3)
    return {
        "regions_mm": reg,
        "touch_mm2": area * len(reg),
        "solidity": 0.0,
        "descriptors": np.zeros(desc_size(N_HARMONICS_MAX)),
        "grid": np.zeros(N_GRID),
        "fingers": len(tips),
        "contacts_canon": np.zeros((0, 2)),
    }


def test_a_fingertip_seen_in_two_pieces_is_one_fingertip():
    rec = _rec([(100.0, 100.0), (130.0, 100.0)])
    # the first fingertip split by a dim band: a piece 5 mm from the rest of it
    rec["regions_mm"] = np.array([[90.0, 98.0, 100.0], [40.0, 103.0, 100.0], [120.0, 130.0, 100.0]])
    tips = tips_mm(rec)
    assert len(tips) == 2
    assert abs(np.linalg.norm(tips[0] - tips[1]) - 30.0) < 1.5  # the fingertips' spacing


def test_a_region_in_one_frame_of_a_held_pose_is_no_fingertip():
    """One fingertip held for 4 frames; a knuckle brushes the glass 21 mm from it in one."""
    recs = [_rec([(100.0, 100.0)]) for _ in range(4)]
    recs[2] = _rec([(100.0, 100.0), (100.0, 121.0)])
    x = select_static(static_features(recs, N_HARMONICS_MAX, 4)[None, :], 0, N_HARMONICS_MAX)
    phys = x[0, :]
    assert phys[COUNT_INDEX] == 1.0
    assert phys[STATIC_NAMES.index("top2_spacing_mm")] == 0.0


def test_fingers_trembling_each_their_own_way_do_not_move_a_resting_hand():
    """Two resting fingertips: one trembles by 1.5 mm a frame; the other's four chance
    positions happen to lie near a line 2.6 mm long. Each alone would judge its jitter by
    its own two residuals; the hand's fingertips tremble alike."""
    a = [(100.0, 100.0), (101.5, 98.6), (98.4, 101.2), (100.9, 99.5)]
    b = [(130.0, 100.0), (130.8, 100.1), (131.8, 99.9), (132.6, 100.0)]
    m = physical_motion([_rec([p, q]) for p, q in zip(a, b, strict=True)])
    assert m[MOTION_NAMES.index("track_dmax_mm")] < TREMOR_MM


def _two(step: float, turn_deg: float = 0.0, still: bool = False) -> np.ndarray:
    """Motion of two fingertips 40 mm apart over 4 frames: parting by ``step`` mm a frame
    each (``still``: one of them resting, as a zoom's thumb), turning ``turn_deg`` a frame
    about their middle."""
    recs = []
    for f in range(4):
        t = np.radians(turn_deg * f)
        u = np.array([np.cos(t), np.sin(t)])
        a = 100 + (20.0 + step * f) * u
        b = 100 - (20.0 + (0.0 if still else step * f)) * u
        recs.append(_rec([tuple(a), tuple(b)]))
    return physical_motion(recs)


def test_the_dynamic_classifier_sees_a_zoom_alike_at_any_speed():
    """A zoom at 1 and at 3 mm a frame (a renderer's people faster than the training
    set's): the motion's shares of shift, arc and spacing change, which the dynamic
    classifier sees beside the lengths, are nearly the same, and a rotate's are not."""
    slow, fast, rotate = _two(1.0), _two(3.0), _two(0.0, 5.0)
    sh = motion_shares(np.vstack([slow, fast, rotate]))
    assert np.abs(sh[0] - sh[1]).max() < 0.1
    assert sh[1, SHARE_PARTS.index("track_spacing_mm")] > 0.7
    assert sh[2, SHARE_PARTS.index("track_arc_mm")] > 0.7
    rows = np.zeros((1, static_size(N_HARMONICS_MAX) + N_MOTION))
    rows[0, -len(MOTION_NAMES) :] = fast
    view = select_dynamic(rows, 0, N_HARMONICS_MAX)[0]
    assert any(np.allclose(view[i : i + 3], sh[1]) for i in range(len(view) - 2))


def test_a_knuckle_brushing_the_glass_in_the_last_frame_is_no_meeting_of_fingertips():
    """A zoom's two fingertips parting; a curled finger's knuckle touches the glass 40 mm
    away in the window's last frame only: no fingertips met or parted (a model trained
    where only piles change their count read such zooms as piles)."""
    recs = [_rec([(100.0 - 20 - 2 * f, 100.0), (100.0 + 20 + 2 * f, 100.0)]) for f in range(4)]
    recs[3] = _rec([(74.0, 100.0), (126.0, 100.0), (100.0, 140.0)])
    assert physical_motion(recs)[MOTION_NAMES.index("tips_met")] == 0
    pile = [_rec([(100.0 + 25 * i, 100.0) for i in range(n)]) for n in (5, 5, 3, 3)]
    assert physical_motion(pile)[MOTION_NAMES.index("tips_met")] == 2


def test_a_pointing_hand_under_dim_light_is_found_in_every_frame():
    """The phalanx renderer's one_finger at x0.7 light: the hovering hand's brightest
    block falls just short of a seed in most frames, and its fingertip alone is too small
    for a hand; the hand is found in each of its frames, in the same place."""
    from plugins.gestures.features import frame_record
    from plugins.gestures.renderer_sets import _phalanx_samples
    from plugins.gestures.vision import VisionParams, process_frame

    _, _, frames, bg, _ = next(_phalanx_samples(1, 1, 97, 0.7, False, ("one_finger",)))
    recs = [frame_record(process_frame(img, bg, VisionParams())) for img in frames[:4]]
    assert all(r is not None for r in recs)
    palms = np.array([r["palm_px"] for r in recs])
    assert np.ptp(palms, axis=0).max() < 15.0
