"""Flow plans computed in the planner's process equal the ones computed here, sample for
sample; closing the planner while it computes ends the wait with one line."""

from __future__ import annotations

import threading
import time

import numpy as np
import pytest

from console.core.errors import UserError
from plugins.demos.adapters import flow_renderers
from plugins.demos.planner import PlanProcess


@pytest.fixture
def map_path(tmp_path):
    from console.files.vibration_map import save_map
    from plugins.vibrotactile.analytic_plate import SSPlate, analytic_map

    path = tmp_path / "map.npz"
    save_map(path, analytic_map(SSPlate()))
    return path


def _same(a, b) -> None:
    assert a.meta["parts"] == b.meta["parts"]
    assert len(a.segments) == len(b.segments)
    for sa, sb in zip(a.segments, b.segments, strict=True):
        assert sa.patches == sb.patches
        np.testing.assert_array_equal(sa.piezo_v, sb.piezo_v)


def test_plans_from_the_planner_process_equal_local_ones(profile, plugins, map_path):
    planner = PlanProcess(profile)
    try:
        remote_hand, remote_pairs = flow_renderers(plugins, profile, map_path, planner)
        local_hand, local_pairs = flow_renderers(plugins, profile, map_path)
        _same(remote_hand.plan((300.0, 200.0), "up"), local_hand.plan((300.0, 200.0), "up"))
        a, b = (200.0, 150.0), (450.0, 250.0)
        _same(remote_pairs.plan(a, b), local_pairs.plan(a, b))
        assert remote_hand.cached((300.0, 200.0), "up") is not None  # kept here after
        with pytest.raises(UserError, match="direction"):
            remote_hand.plan((300.0, 200.0), "sideways")
    finally:
        planner.close()


def test_closing_the_planner_ends_a_wait_under_way(profile, plugins, map_path):
    planner = PlanProcess(profile)
    hand, _ = flow_renderers(plugins, profile, map_path, planner)
    got: list = []

    def ask() -> None:
        try:
            got.append(hand.plan((350.0, 250.0), "left"))
        except UserError as exc:
            got.append(exc)

    t = threading.Thread(target=ask)
    t.start()
    time.sleep(0.3)  # the request is in the worker (still starting or computing)
    planner.close()
    t.join(10)
    assert not t.is_alive()
    # the worker needs seconds to start and plan: the wait was cut short, in one line
    assert len(got) == 1 and isinstance(got[0], UserError) and "ended" in str(got[0])
    assert not planner._proc.is_alive()
