"""A slow start: by the 4th frame a spread's fingertips have each moved about a
millimetre, under the tremor floor the moving fingertips are counted at, like a zoom's
two while curled fingers rest. The second and third largest displacements still tell
them apart, and the dynamic classifier sees them whole (the twin's slow spreads read as
zooms and its slow zooms as spreads: LOSO dynamic-only 0.924 -> 0.960)."""

from __future__ import annotations

import numpy as np

from plugins.gestures.features import N_MOTION, select_dynamic, select_kind, static_size
from plugins.gestures.physical import MOTION_NAMES, motion_view, physical_motion


def _recs(tracks_mm: list[list[tuple[float, float]]]) -> list[dict]:
    out = []
    for f in range(len(tracks_mm[0])):
        reg = np.array([[120.0, *t[f]] for t in tracks_mm])
        out.append({"regions_mm": reg, "touch_mm2": 120.0 * len(reg), "solidity": 0.0})
    return out


def _slow(direction: tuple[float, float], start: tuple[float, float], step: float):
    """A fingertip easing out along ``direction``: 0, 0.1, 0.35, 0.7 of ``step`` x 3."""
    d = np.asarray(direction, float) / np.linalg.norm(direction)
    return [tuple(np.asarray(start) + 3 * step * e * d) for e in (0.0, 0.1, 0.35, 0.7)]


SPREAD = [_slow(d, (20 * d[0], 20 * d[1]), 0.6) for d in ((1, 0), (0, 1), (-1, 0), (0, -1))]
ZOOM = [_slow((0, -1), (0, -10), 0.6), _slow((0, 1), (0, 10), 0.6),
        [(30.0, 30.0)] * 4, [(-30.0, 30.0)] * 4]  # fmt: skip


def test_the_second_and_third_fingertips_tell_a_slow_spread_from_a_slow_zoom():
    d2, d3 = MOTION_NAMES.index("track_d2_mm"), MOTION_NAMES.index("track_d3_mm")
    moving = MOTION_NAMES.index("tracks_moving")
    spread, zoom = physical_motion(_recs(SPREAD)), physical_motion(_recs(ZOOM))
    assert spread[moving] == zoom[moving] == 0  # each under the tremor floor
    assert spread[d3] > 0.5 and zoom[d3] == 0.0
    assert spread[d2] > 0.5 and zoom[d2] > 0.5
    view = motion_view(np.vstack([spread, zoom]))
    assert view[0, d3] > 0.3 and view[1, d3] == 0.0  # not cut at the floor


def test_the_dynamic_classifier_sees_the_ranks_and_the_kind_classifier_does_not():
    rows = np.zeros((2, N_MOTION))
    rows[:, N_MOTION - len(MOTION_NAMES) :] = physical_motion(_recs(SPREAD))
    for name in ("track_d2_mm", "track_d3_mm"):  # the same motion but for the ranks
        rows[1, N_MOTION - len(MOTION_NAMES) + MOTION_NAMES.index(name)] = 0.0
    kind = select_kind(rows)
    assert np.array_equal(kind[0], kind[1])  # whether it moves: not from the ranks
    full = np.hstack([np.zeros((2, static_size(16))), rows])
    dyn = select_dynamic(full, 0, 16)
    assert not np.array_equal(dyn[0], dyn[1])
