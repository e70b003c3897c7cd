"""Knob sectors: crossings, hysteresis, fast turns, menu ends."""

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from plugins.electrostatic.knob import Knob


def test_crossings_follow_the_boundaries_in_order():
    k = Knob(8)  # 45 deg sectors, start on item 0 (0-45 deg)
    items = []
    for a in np.linspace(22.5, 150.0, 200):
        items += [c.to_item for c in k.update(0.0, a)]
    assert items == [1, 2, 3]
    assert k.item == 3
    back = [c.direction for a in np.linspace(150.0, 60.0, 100) for c in k.update(1.0, a)]
    assert back == [-1, -1]


def test_jitter_on_a_boundary_does_not_chatter():
    rng = np.random.default_rng(0)
    jitter = 45.0 + rng.uniform(-0.9, 0.9, 500)  # on the boundary between items 0 and 1
    k = Knob(8, hysteresis_deg=1.0)
    n = sum(len(k.update(0.0, a)) for a in jitter)
    assert n <= 1
    # without hysteresis the same jitter chatters
    k0 = Knob(8, hysteresis_deg=0.0)
    assert sum(len(k0.update(0.0, a)) for a in jitter) > 50


def test_a_fast_turn_gives_one_crossing_per_boundary():
    k = Knob(32)
    cr = k.update(0.5, 100.0)  # from item 0 straight into item 8
    assert [c.to_item for c in cr] == list(range(1, 9))
    assert all(c.t_s == 0.5 for c in cr)


def test_menu_ends_stop_the_selection():
    k = Knob(16, start_item=1, n_items=3)
    k.update(0.0, 500.0)
    assert k.item == 2
    k.update(0.0, -500.0)
    assert k.item == 0
    assert k.update(0.0, float("nan")) == []


def test_geometry_helpers_and_bad_hysteresis():
    k = Knob(16)
    assert k.center_deg(3) == pytest.approx(78.75)
    assert k.boundary_distance(22.5 + 2.0) == pytest.approx(2.0)
    with pytest.raises(ValueError):
        Knob(32, hysteresis_deg=6.0)


@settings(max_examples=200, deadline=None)
@given(
    sectors=st.sampled_from([8, 16, 32]),
    angles=st.lists(st.floats(-1000, 1000, allow_nan=False), min_size=1, max_size=60),
)
def test_selection_is_the_sector_under_the_angle_and_crossings_add_up(sectors, angles):
    h = 1.0
    k = Knob(sectors, hysteresis_deg=h)
    w = 360.0 / sectors
    for a in angles:
        before = k.item
        cr = k.update(0.0, a)
        assert k.item - before == sum(c.direction for c in cr)
        assert all(abs(c.to_item - c.from_item) == 1 for c in cr)
        # away from a boundary the selection is exactly the sector under the angle
        r = a % w
        if h < r < w - h:
            assert k.item == int(a // w)
        else:  # within the hysteresis band: one of the two neighbours
            assert abs(k.item - round(a / w)) <= 1
