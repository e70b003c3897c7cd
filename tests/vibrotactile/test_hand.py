"""Flow under a hand (paper 5.2.2): the square rule, symmetry, directions, screening."""

from __future__ import annotations

import math

import numpy as np
import pytest

from console.core.errors import UserError
from plugins.vibrotactile.hand import (
    DIRECTIONS,
    choose,
    hand_flow,
    hand_flow_table,
    side_masks,
    square_levels,
)
from plugins.vibrotactile.interp import interpolate
from plugins.vibrotactile.thresholds import Perception

PER = Perception()
C = (300.0, 200.0)


@pytest.fixture(scope="module")
def levels(ss_map):
    return square_levels(ss_map, C)


def test_half_the_subgrid_rule_matches_a_direct_count(ss_map, levels):
    q, keep = levels
    e, k = 4, 300
    sub = 120 / 45
    xs = C[0] - 60 + (np.arange(15) + 0.5) * sub  # square (row 0, col 0)
    ys = C[1] - 60 + (np.arange(15) + 0.5) * sub
    pts = np.array([(x, y) for y in ys for x in xs])
    amp = np.abs(interpolate(ss_map, pts)[e, :, keep[k]])
    level = q[e, 0, 0, k]
    # "at least half" at this level and not above it (square levels are float32)
    assert (amp >= level * (1 - 1e-5)).sum() >= math.ceil(225 / 2)
    assert (amp > level * (1 + 1e-5)).sum() < math.ceil(225 / 2)


@pytest.mark.parametrize("direction", DIRECTIONS)
def test_active_side_then_mirror_side(ss_map, levels, direction):
    q, keep = levels
    r = choose(q, keep, ss_map, direction, PER, 95.0)
    assert r["ok"]
    start, end = side_masks(direction)
    for part, (a, b) in zip(r["parts"], ((start, end), (end, start)), strict=True):
        act = np.array(part["active"])
        assert act[a].any() and not act[b].any()  # the mirror side stays passive
        assert part["margin_db"] > 0 and 0 < part["amplitude_v"] <= 95.0
    lv = [20 * np.log10(p["qa"] * p["amplitude_v"] / p["x_um"]) for p in r["parts"]]
    assert lv[0] == pytest.approx(lv[1], abs=1e-6)  # equal level above the 3-JND line


def test_left_is_right_reversed(ss_map, levels):
    q, keep = levels
    right = choose(q, keep, ss_map, "right", PER, 95.0)["parts"]
    left = choose(q, keep, ss_map, "left", PER, 95.0)["parts"]
    assert (left[0]["actuator"], left[0]["frequency_hz"]) == (
        right[1]["actuator"],
        right[1]["frequency_hz"],
    )


def test_side_masks_are_mirror_images():
    for d in DIRECTIONS:
        s, e = side_masks(d)
        assert s.sum() == e.sum() == 3
        assert np.array_equal(s, e[:, ::-1]) or np.array_equal(s, e[::-1, :])
    with pytest.raises(UserError, match="direction"):
        side_masks("diagonal")


@pytest.mark.slow
def test_screen_then_exact_is_close_to_exhaustive(ss_map):
    """The screened sweep re-scores its candidates exactly: never better than the
    exhaustive search, and close to it (the bench reports how often it is identical)."""
    for c in ((200.0, 150.0), (450.0, 250.0)):
        ex = hand_flow(ss_map, c, "up", PER)
        sc = hand_flow(ss_map, c, "up", PER, screen_stride=3)
        for a, b in zip(sc["parts"], ex["parts"], strict=True):
            assert a["margin_db"] <= b["margin_db"] + 1e-6
            assert a["margin_db"] >= b["margin_db"] - 3.0


def test_hand_size_and_edges(ss_map):
    small = hand_flow(ss_map, C, "right", PER, hand_mm=85.0, screen_stride=3)
    assert small["hand_mm"] == 85.0 and len(small["parts"][0]["active"]) == 3
    with pytest.raises(UserError, match="outside the measured grid"):
        hand_flow(ss_map, (60.0, 200.0), "right", PER)  # the hand hangs over the grid edge


def test_table_of_regions(ss_map):
    t = hand_flow_table(ss_map, PER, centers=np.array([C, (400.0, 250.0)]))
    assert t["ok"].shape == (2, 4) and t["active"].shape == (2, 4, 2, 3, 3)
    one = hand_flow(ss_map, C, "down", PER, screen_stride=3)
    j = DIRECTIONS.index("down")
    assert t["frequency_hz"][0, j, 0] == one["parts"][0]["frequency_hz"]


@pytest.mark.parametrize("center", [(200.0, 150.0), (500.0, 260.0)])
def test_closed_loop_exact_plate_under_the_hand(ss_plate, ss_map, center):
    """Decisions made on interpolated FRFs hold on the exact plate: in each part the
    start (then end) side has an active square and its mirror side none."""
    offs = (np.arange(45) + 0.5) * 120 / 45 - 60
    pts = np.array([(center[0] + x, center[1] + y) for y in offs for x in offs])
    for d in DIRECTIONS:
        r = hand_flow(ss_map, center, d, PER, screen_stride=3)
        assert r["ok"]
        s, e = side_masks(d)
        for part, (a, b) in zip(r["parts"], ((s, e), (e, s)), strict=True):
            h = np.abs(
                ss_plate.frf_um_per_v(pts, [part["frequency_hz"]], (part["actuator"],))[0, :, 0]
            )
            sq = h.reshape(3, 15, 3, 15).transpose(0, 2, 1, 3).reshape(3, 3, 225)
            q = -np.sort(-sq, axis=-1)[..., 112]  # 113th largest: at least half of 225
            active = q * part["amplitude_v"] >= part["x_um"]
            assert active[a].any() and not active[b].any()
