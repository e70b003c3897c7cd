"""Stimuli played through the safety gate and scheduler on the sim profile's twin outputs."""

from __future__ import annotations

import numpy as np

from plugins.vibrotactile.stimuli import StimulusSettings, flow_plan, point_plan
from plugins.vibrotactile.thresholds import Perception


def test_flow_plays_through_the_gate_with_relays_switched_between_parts(
    outputs, profile, ss_tables
):
    st = StimulusSettings(
        sample_rate_hz=int(profile.get("audio.sample_rate_hz")), part_s=0.3, ramp_ms=20
    )
    act = ss_tables.actuator
    a, b = next(
        (a, b)
        for a in range(84)
        for b in range(84)
        if a != b and act[a, b] != act[b, a] and 4 not in (act[a, b], act[b, a])
    )
    plan = flow_plan(ss_tables, a, b, Perception(), st, piezo_min_v=-100, piezo_max_v=100)
    assert plan.segments[0].patches != plan.segments[1].patches
    outputs.play(plan)
    rec = outputs.recording()
    assert rec is not None
    played = rec[:, 0]
    want = max(np.abs(s.piezo_v).max() for s in plan.segments)
    assert np.abs(played).max() == pytest_approx(want)
    log = outputs.relay_log()
    channels = {n: profile.get(f"patches.{n}.relay_channel") for n in ("PA", "PB", "PC", "PD")}
    closed = [channels[p] for s in plan.segments for p in sorted(s.patches)]
    assert {r.channel for r in log if r.closed} >= set(closed)  # each part's patch relay closed
    assert all(max(abs(v) for v in r.level_v) < 1e-6 for r in log)  # only ever in silence


def test_point_pulse_plays(outputs, profile, ss_tables):
    st = StimulusSettings(
        sample_rate_hz=int(profile.get("audio.sample_rate_hz")), pulse_s=0.2, ramp_ms=20
    )
    outputs.play(point_plan(ss_tables, 10, Perception(), st))
    assert np.abs(outputs.recording()[:, 0]).max() > 0


def pytest_approx(v):
    import pytest

    return pytest.approx(v, rel=1e-3)
