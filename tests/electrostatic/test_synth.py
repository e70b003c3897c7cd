"""The live knob stream: conditions, ramps, click-free changes, detent timing, limits."""

import threading

import numpy as np
import pytest

from console.core.contracts import StreamSource
from console.core.errors import UserError
from plugins.electrostatic.settings import KNOB_DEFAULTS
from plugins.electrostatic.synth import CONDITIONS, Envelope, KnobStream, parse_condition

FS, B = 48000, 64


def render(s, n_blocks, events=None):
    out_p, out_s = [], []
    for k in range(n_blocks):
        if events and k in events:
            s.post(**events[k])
        b = s.next_block(B)
        if b is None:
            break
        out_p.append(b[0])
        out_s.append(b[1])
    return np.concatenate(out_p), np.concatenate(out_s)


def test_conditions_parse_and_unknown_names_say_what_exists():
    assert parse_condition("hd+vf").friction == "velocity"
    assert parse_condition("VD+CF").detent == "piezo"
    for c in CONDITIONS:
        assert parse_condition(c).name == c
    with pytest.raises(UserError, match="HD\\+VF"):
        parse_condition("HD+XX")


def test_is_a_stream_source_and_v_is_silent():
    s = KnobStream("V", FS)
    assert isinstance(s, StreamSource)
    assert not s.screen and s.patches == frozenset()
    p, x = render(s, 100, {10: {"crossings": 3, "velocity_deg_s": 200.0}})
    assert not np.any(p) and not np.any(x)


def test_start_and_stop_ramps():
    s = KnobStream("HD+CF", FS, {**KNOB_DEFAULTS, "ramp_ms": 10.0})
    _, x = render(s, 60)
    ramp_n = 480
    assert x[0] == 0.0  # the gate requires a live stream to start from zero
    # the envelope of the first 10 ms grows; after it the sine has full amplitude
    assert np.abs(x[:48]).max() < 0.1 * np.abs(x[ramp_n : ramp_n + 480]).max()
    assert np.abs(x[ramp_n:]).max() == pytest.approx(50.0, abs=0.5)
    s.request_stop()
    _, y = render(s, 100)
    assert 470 <= y.size <= 480 + B  # about ramp_ms, then None
    assert s.next_block(B) is None and s.done
    assert abs(y[-1]) < 0.5
    assert np.abs(y[-48:]).max() < 0.1 * 50.0


def test_frequency_changes_are_phase_continuous():
    s = KnobStream("HD+VF", FS)
    rng = np.random.default_rng(0)
    ev = {k: {"velocity_deg_s": float(rng.uniform(-400, 400))} for k in range(0, 600, 3)}
    _, x = render(s, 600, ev)
    a = KNOB_DEFAULTS["carrier_vpp"] / 2
    slope = 2 * np.pi * KNOB_DEFAULTS["vf_freq_at_speed_hz"] * a / FS
    assert np.max(np.abs(np.diff(x))) <= slope * 1.01
    assert np.all(np.isfinite(x))


def test_a_crossing_starts_its_detent_in_the_next_block_with_alternating_polarity():
    s = KnobStream("HD", FS)
    _, x = render(s, 200, {50: {"crossings": 1}, 120: {"crossings": 1}})
    on = np.nonzero(np.abs(x) > 1e-9)[0]
    first = on[0]
    assert first == 50 * B  # the block that followed the post
    assert np.abs(x[: 50 * B]).max() == 0.0
    second = on[on >= 120 * B][0]
    assert second == 120 * B
    assert np.sign(x[first + 100]) == -np.sign(x[second + 100])
    assert np.abs(x).max() == pytest.approx(KNOB_DEFAULTS["detent_vpp"] / 2)
    pulse_n = np.count_nonzero(np.abs(x[first : first + 2000]) > 1e-9)
    assert pulse_n == pytest.approx(KNOB_DEFAULTS["detent_ms"] * FS / 1000, abs=2)


def test_detent_edges_and_ducking_bound_the_slope_and_the_peak():
    s = KnobStream("HD+CF", FS)
    ev = {k: {"crossings": 1} for k in range(20, 400, 7)}  # crossings faster than detents
    _, x = render(s, 400, ev)
    edge_n = KNOB_DEFAULTS["detent_edge_ms"] * FS / 1000
    a = 50.0
    bound = 2 * a * np.pi / (2 * edge_n) + 2 * np.pi * 180 * a / FS
    assert np.max(np.abs(np.diff(x))) <= bound
    assert np.abs(x).max() <= 50.0 + 1e-9


def test_boundary_variant_is_stronger_at_boundaries():
    s = KnobStream("HD+BF", FS, sectors=8)
    _, mid = render(s, 100, {0: {"angle_deg": 22.5}})
    s2 = KnobStream("HD+BF", FS, sectors=8)
    _, edge = render(s2, 100, {0: {"angle_deg": 44.0}})
    assert np.abs(edge[-2000:]).max() > 2 * np.abs(mid[-2000:]).max()
    assert np.abs(mid[-2000:]).max() == pytest.approx(KNOB_DEFAULTS["bf_min_vpp"] / 2, rel=0.02)


def test_vibrotactile_detent_variant_uses_the_piezo_channel():
    s = KnobStream("VD+VF", FS)
    assert s.patches == frozenset({"PA", "PB", "PC", "PD"}) and s.screen
    p, x = render(s, 200, {100: {"crossings": 1}})
    assert np.abs(p[: 100 * B]).max() == 0.0
    assert np.abs(p[100 * B : 101 * B]).max() > 0.0
    assert np.abs(p).max() <= KNOB_DEFAULTS["vd_peak_v"]
    assert np.abs(x[-4000:]).max() == pytest.approx(50.0, abs=0.5)  # friction keeps going


def test_limits_are_refused_and_bad_inputs_give_no_nan():
    with pytest.raises(UserError, match="screen_max_vpp"):
        KnobStream("HD+CF", FS, {**KNOB_DEFAULTS, "carrier_vpp": 300.0})
    with pytest.raises(UserError, match="vd_peak_v"):
        KnobStream("VD+CF", FS, {**KNOB_DEFAULTS, "vd_peak_v": 150.0})
    s = KnobStream("HD+VF", FS)
    p, x = render(s, 50, {5: {"velocity_deg_s": float("nan"), "angle_deg": float("inf")}})
    assert np.all(np.isfinite(x)) and np.all(np.isfinite(p))


def test_lifting_the_fingers_fades_the_friction():
    s = KnobStream("HD+CF", FS)
    _, x = render(s, 200, {100: {"touching": False}})
    assert np.abs(x[-2000:]).max() < 1e-6
    assert np.max(np.abs(np.diff(x))) <= 2 * np.pi * 180 * 50 / FS * 1.01


def test_posting_from_another_thread_loses_no_crossing():
    s = KnobStream("HD", FS)
    n = 300

    def poster():
        for _ in range(n):
            s.post(crossings=1)

    th = threading.Thread(target=poster)
    th.start()
    while th.is_alive():
        s.next_block(B)
    s.next_block(B)
    assert sorted(i for i, _ in s.detent_log) == list(range(n))


def test_envelope_retrigger_is_continuous():
    e = Envelope(10, 5)
    e.trigger()
    a = e.block(22)  # rise 10, hold 5, part of the fall
    e.trigger()  # retrigger while falling: rise again from where it is
    b = e.block(40)
    y = np.concatenate([a, b])
    assert np.max(np.abs(np.diff(y))) <= np.pi / 20 + 1e-12
    assert y[-1] == 0.0 and not e.active


def test_stop_before_the_first_block_ends_cleanly():
    s = KnobStream("HD+CF", FS)
    s.request_stop()
    b = s.next_block(B)
    assert b is not None and not np.any(b[1])
    assert s.next_block(B) is None
