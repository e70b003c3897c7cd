"""Flow and point stimuli: plans the safety gate accepts, right frequencies and patches,
equal sensation level, ramps, relays switched between segments."""

from __future__ import annotations

import numpy as np
import pytest

from console.core.errors import UserError
from console.core.types import patches_of
from console.safety import Limits, check_plan
from plugins.vibrotactile.stimuli import StimulusSettings, flow_plan, point_plan
from plugins.vibrotactile.tables import build_tables, query_indices
from plugins.vibrotactile.thresholds import Perception

LIMITS = Limits(
    sample_rate_hz=48000,
    piezo_min_v=-100,
    piezo_max_v=250,
    screen_max_v=100,
    piezo_card_v=100,
    screen_card_v=100,
    rating_vpp=350,
    ramp_samples=240,
    max_plan_samples=48000 * 60,
    guard_samples=240,
    settle_samples=336,
    estop_timeout_s=0.05,
)
ST = StimulusSettings()
PER = Perception()


def peak_freq(x, fs):
    spec = np.abs(np.fft.rfft(x * np.hanning(x.size), 8 * x.size))
    return np.argmax(spec) * fs / (8 * x.size)


def test_flow_plan_follows_tables_and_passes_gate(ss_tables):
    plan = flow_plan(ss_tables, 50, 51, PER, ST, piezo_min_v=-100, piezo_max_v=100)
    check_plan(plan, LIMITS)
    assert len(plan.segments) == 2 and plan.duration_s == pytest.approx(3.0)
    for seg, (a, p) in zip(plan.segments, ((50, 51), (51, 50)), strict=True):
        ans = query_indices(ss_tables, a, p)
        assert seg.patches == patches_of(ans["actuator"])
        assert peak_freq(seg.piezo_v, 48000) == pytest.approx(ans["frequency_hz"], abs=0.5)
        assert seg.piezo_v[0] == 0 and abs(seg.piezo_v[-1]) < 1e-9
        nr = int(ST.ramp_ms * 48)
        peak = np.abs(seg.piezo_v).max()
        assert np.all(np.abs(seg.piezo_v[:nr]) <= peak * np.arange(nr) / nr + 1e-9)  # linear ramp
        assert np.all(seg.screen_v == 0) and not seg.screen


def test_both_parts_at_equal_sensation_level(ss_tables):
    plan = flow_plan(ss_tables, 50, 51, PER, ST)
    sls = []
    for part in plan.meta["parts"]:
        disp_um = part["active_um_per_v"] * part["amplitude_v"]
        sls.append(20 * np.log10(disp_um) - PER.threshold_db(part["frequency_hz"], "fingertip"))
    assert sls[0] == pytest.approx(sls[1], abs=0.01)
    assert sls[0] == pytest.approx(plan.meta["sensation_level_db"], abs=0.01)
    # the frequencies differ, so the voltages differ by the threshold curve and the FRFs
    assert plan.meta["parts"][0]["amplitude_v"] != pytest.approx(
        plan.meta["parts"][1]["amplitude_v"]
    )


def test_closed_loop_active_beats_passive(ss_plate, ss_tables):
    """Exact plate response to each part at the two points: the active side wins."""
    plan = flow_plan(ss_tables, 50, 51, PER, ST)
    xy = ss_tables.vmap.points_mm[[50, 51]]
    for i, part in enumerate(plan.meta["parts"]):
        e = ss_tables.excitations.index(part["actuator"])
        h = np.abs(ss_plate.frf_um_per_v(xy, [part["frequency_hz"]], (part["actuator"],))[0, :, 0])
        active, passive = (h[0], h[1]) if i == 0 else (h[1], h[0])
        assert active - passive == pytest.approx(part["max_difference_um_per_v"], rel=1e-6)
        assert e >= 0 and active > passive


def test_weak_map_caps_voltage_and_says_so(ss_map):
    from console.files.vibration_map import VibrationMap

    weak = VibrationMap(
        ss_map.frf_um_per_v * 1e-4,
        ss_map.freq_hz,
        ss_map.points,
        ss_map.points_mm,
        ss_map.excitations,
        ss_map.masked,
    )
    plan = flow_plan(build_tables(weak), 50, 51, PER, ST, piezo_min_v=-100, piezo_max_v=100)
    assert max(np.abs(s.piezo_v).max() for s in plan.segments) <= ST.drive_max_v + 1e-9
    assert plan.meta["notes"] and "sensation level" in plan.meta["notes"][0]
    check_plan(plan, LIMITS)


def test_same_point_flow_refused(ss_tables):
    with pytest.raises(UserError, match="same point"):
        flow_plan(ss_tables, 10, 10, PER, ST)


def test_flow_between_arbitrary_points(ss_tables):
    plan = flow_plan(ss_tables, (250.0, 200.0), (330.0, 200.0), PER, ST)
    check_plan(plan, LIMITS)
    assert plan.meta["parts"][0]["active_um_per_v"] > plan.meta["parts"][0]["passive_um_per_v"]


def test_point_pulse_at_strongest_frequency(ss_map, ss_tables):
    plan = point_plan(ss_tables, 50, PER, ST)
    check_plan(plan, LIMITS)
    ok = ~ss_map.masked & (ss_map.freq_hz <= 650)
    amp = np.abs(ss_map.frf_um_per_v[:, 50, :])
    amp[:, ~ok] = 0
    e, k = np.unravel_index(np.argmax(amp), amp.shape)
    assert plan.meta["frequency_hz"] == ss_map.freq_hz[k]
    assert plan.segments[0].patches == patches_of(ss_map.excitations[e])


def test_perception_curve_is_u_shaped_and_validated():
    f = np.array([20, 100, 250, 400, 700])
    t = PER.threshold_db(f)
    assert np.argmin(t) == 2 and t[0] == 12
    assert PER.threshold_db(250, "fingertip") == pytest.approx(-14)
    with pytest.raises(UserError, match="same length"):
        Perception((10.0, 20.0), (1.0,))
