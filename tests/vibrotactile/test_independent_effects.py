"""The ``independent`` method of the ``flow`` and ``point`` effects: per-patch segments on
a profile with a channel per patch, refused in one line on the paper's bus."""

from __future__ import annotations

from dataclasses import replace

import numpy as np
import pytest

from console.core.errors import UserError

FOUR = ["PA", "PB", "PC", "PD", "screen"]


def with_channels(profile, names, **vt):
    audio = {**profile.section("audio"), "channels": list(names)}
    vib = {**profile.section("vibrotactile"), **vt}
    return replace(profile, data={**profile.data, "audio": audio, "vibrotactile": vib})


@pytest.fixture
def bus_effects(ctx):
    prof = with_channels(ctx.profile, ["piezo", "screen"], cache_dir="none")
    return {n: ctx.pm.get("effect", n).factory(prof) for n in ("flow", "point")}


@pytest.fixture
def four_effects(ctx):
    prof = with_channels(ctx.profile, FOUR, cache_dir="none")
    return {n: ctx.pm.get("effect", n).factory(prof) for n in ("flow", "point")}


def test_bus_profile_keeps_the_paper_and_refuses_independent(bus_effects, ss_map):
    plan = bus_effects["flow"].render(10, 40, vmap=ss_map)
    assert not any(s.independent for s in plan.segments)
    for name, kw in (("flow", {"from_point": 10, "to_point": 40}), ("point", {"point": 10})):
        with pytest.raises(UserError) as exc:
            bus_effects[name].render(vmap=ss_map, method="independent", **kw)
        msg = str(exc.value)
        assert "\n" not in msg and "[audio] channels" in msg and "'paper'" in msg


def test_four_channels_flow_is_per_patch(four_effects, ss_map):
    flow = four_effects["flow"]
    plan = flow.render(10, 40, vmap=ss_map)  # auto: independent on four channels
    paper = flow.render(10, 40, vmap=ss_map, method="paper")
    assert plan.meta["method"] == "independent" and paper.meta["method"] == "paper"
    assert flow.cached(10, 40, vmap=ss_map) is plan
    assert flow.cached(10, 40, vmap=ss_map, method="paper") is paper
    cap = flow.setup.cap_v
    assert len(plan.segments) == 2
    for seg, part in zip(plan.segments, plan.meta["parts"], strict=True):
        assert seg.independent and seg.patches == frozenset(("PA", "PB", "PC", "PD"))
        assert seg.bus_drive() is None  # the patches play different drives
        for p, v in seg.drives().items():
            assert v[0] == 0.0 and abs(v[-1]) < 1e-9  # ramps to 0 V at both ends
            assert np.abs(v).max() == pytest.approx(part["patch_v"][p], rel=1e-3, abs=1e-9)
            assert np.abs(v).max() <= cap + 1e-9
        assert max(part["patch_v"].values()) == pytest.approx(part["amplitude_v"])
    # the map says it localises better than the paper's tables, by a wide margin
    worst_paper = min(p["contrast_db"] for p in paper.meta["parts"])
    assert min(p["contrast_db"] for p in plan.meta["parts"]) >= worst_paper + 6.0
    # the expected contrast (with the map's error) is the lower bound shown to operators
    assert plan.meta["predicted_contrast_db"] == pytest.approx(
        min(p["expected_contrast_db"] for p in plan.meta["parts"])
    )
    # equal sensation level in both parts (paper Fig. 9)
    sl = [
        20 * np.log10(p["active_um_per_v"] * p["amplitude_v"]) - p["threshold_db"]
        for p in plan.meta["parts"]
    ]
    assert sl[0] == pytest.approx(sl[1], abs=1e-6)


def test_four_channels_flow_between_mm_points_and_same_point(four_effects, ss_map):
    flow = four_effects["flow"]
    plan = flow.render((100.0, 120.0), (400.0, 300.0), vmap=ss_map, method="time_reversal")
    assert plan.meta["method"] == "time_reversal" and plan.meta["from_mm"] == [100.0, 120.0]
    with pytest.raises(UserError, match="same"):
        flow.render(10, 10, vmap=ss_map, method="independent")


def test_four_channels_point_focus(four_effects, ss_map):
    point = four_effects["point"]
    plan = point.render(point=30, vmap=ss_map)
    m = plan.meta
    assert m["method"] == "independent" and plan.segments[0].independent
    assert m["amplitude_v"] <= point.setup.cap_v + 1e-9
    # at the chosen bin the focus beats time reversal against the grid's RMS (its objective)
    tr = point.render(point=30, vmap=ss_map, method="time_reversal").meta
    assert m["contrast_db"] >= tr["contrast_db"] - 1e-6 or m["frequency_hz"] != tr["frequency_hz"]
    assert m["um_per_v"] > m["median_grid_um_per_v"]


def test_four_channels_hand_flow(ctx, ss_map):
    prof = with_channels(ctx.profile, FOUR, cache_dir="none")
    hand = ctx.pm.get("effect", "hand_flow").factory(prof)
    plan = hand.render(center_mm=(300.0, 200.0), direction="right", vmap=ss_map)
    assert plan.meta["method"] == "independent" and len(plan.segments) == 2
    assert all(s.independent for s in plan.segments)
    assert hand.cached((300.0, 200.0), "right", vmap=ss_map) is plan
    assert plan.meta["predicted_contrast_db"] == min(p["contrast_db"] for p in plan.meta["parts"])
    for seg, part in zip(plan.segments, plan.meta["parts"], strict=True):
        peak = max(np.abs(v).max() for v in seg.drives().values())
        assert peak == pytest.approx(part["amplitude_v"], rel=1e-3)
        assert peak <= hand.setup.cap_v + 1e-9
    paper = hand.render(center_mm=(300.0, 200.0), direction="right", vmap=ss_map, method="paper")
    assert paper.meta["method"] == "paper" and not any(s.independent for s in paper.segments)
    bus = ctx.pm.get("effect", "hand_flow").factory(with_channels(ctx.profile, ["piezo", "screen"]))
    with pytest.raises(UserError, match=r"\[audio\] channels"):
        bus.render(center_mm=(300.0, 200.0), direction="right", vmap=ss_map, method="independent")
