"""Twin end to end: simulated two-finger rotation -> tracker -> knob -> stream."""

import numpy as np
import pytest

from plugins.electrostatic.knob import Knob
from plugins.electrostatic.settings import KNOB_DEFAULTS
from plugins.electrostatic.simulate import (
    instantaneous_freq_hz,
    min_jerk,
    rotation_frames,
    run_pipeline,
)

FS, B, FPS = 48000, 64, 60.0
SECTORS = 16


def scenario(seed=0):
    """3.5 s: turn +200 deg, pause, turn back 80 deg; noise, lifts, swaps, a stray touch."""
    t = np.arange(0, 3.5, 1 / FPS)
    true = min_jerk(t, 0.2, 1.5, 0.0, 200.0) + min_jerk(t, 2.2, 1.0, 0.0, -80.0)
    frames = rotation_frames(
        true,
        t,
        noise_mm=0.3,
        lift_frames=[(40, "index", 2), (70, "thumb", 1), (100, "both", 1), (150, "index", 1)],
        swap_frames=[30, 90, 160],
        extra_contact_frames=[55, 56],
        rng=np.random.default_rng(seed),
    )
    return t, true, frames


def start_deg():
    return Knob(SECTORS).center_deg(0)


@pytest.fixture(scope="module")
def hd():
    t, true, frames = scenario()
    return t, true, run_pipeline(frames, "HD", sectors=SECTORS)


def test_the_knob_crosses_the_same_sectors_as_the_true_rotation(hd):
    t, true, r = hd
    ref = Knob(SECTORS, KNOB_DEFAULTS["hysteresis_deg"])
    expected = [
        c.to_item for a, tt in zip(true + start_deg(), t, strict=True) for c in ref.update(tt, a)
    ]
    assert [c.to_item for c in r.crossings] == expected
    assert len(expected) == 9 + 4  # 200 deg forward, 80 back at 22.5 deg per sector


def test_every_detent_starts_within_one_block_of_its_crossing(hd):
    _, _, r = hd
    x = r.screen_v
    on = np.abs(x) > 1e-9
    assert len(r.crossings) > 0
    for c in r.crossings:
        e = c.t_s * FS
        k = int(np.ceil(e))
        window = on[k : k + B]
        assert window.any(), f"no detent within one block of the crossing at {c.t_s:.3f} s"
        if not on[k - 1]:  # a fresh pulse (not the extension of one still playing)
            assert np.argmax(window) + k - e < B
    # and no pulse without a crossing
    onsets = np.nonzero(on[1:] & ~on[:-1])[0] + 1
    cross = np.array([c.t_s * FS for c in r.crossings])
    for o in onsets:
        assert np.any((o - cross >= 0) & (o - cross < B))
    assert np.all(r.latency >= 0) and np.all(r.latency < B)


def test_hd_vf_frequency_follows_the_angular_velocity():
    t, true, frames = scenario(1)
    r = run_pipeline(frames, "HD+VF", sectors=SECTORS)
    x = r.screen_v
    tz, f = instantaneous_freq_hz(x, FS)
    # leave out half periods touched by a detent or the ramps
    busy = np.zeros(x.size, dtype=bool)
    det_n = int(KNOB_DEFAULTS["detent_ms"] * FS / 1000) + 2 * B
    for c in r.crossings:
        k = int(c.t_s * FS)
        busy[k : k + det_n] = True
    busy[: int(0.05 * FS)] = True
    busy[-int(0.05 * FS) :] = True
    keep = ~busy[np.clip((tz * FS).astype(int), 0, x.size - 1)]
    vel = np.abs(np.gradient(true, t))
    s = KNOB_DEFAULTS
    x_v = np.clip(np.interp(tz, t, vel) / s["vf_full_speed_deg_s"], 0, 1)
    f_true = s["vf_freq_at_rest_hz"] + x_v * (s["vf_freq_at_speed_hz"] - s["vf_freq_at_rest_hz"])
    err = np.abs(f[keep] - f_true[keep])
    assert keep.sum() > 500
    assert np.median(err) < 6.0
    assert np.percentile(err, 95) < 30.0  # lag of the velocity filter during accelerations
    # against the velocity the tracker reported (the synthesizer's own job): much tighter
    ts = np.array([st.t_s for st in r.states])
    vs = np.abs([st.velocity_deg_s for st in r.states])
    held = vs[np.clip(np.searchsorted(ts, tz, side="right") - 1, 0, None)]
    f_cmd = s["vf_freq_at_rest_hz"] + np.clip(held / s["vf_full_speed_deg_s"], 0, 1) * (
        s["vf_freq_at_speed_hz"] - s["vf_freq_at_rest_hz"]
    )
    err_cmd = np.abs(f[keep] - f_cmd[keep])
    assert np.median(err_cmd) < 1.0
    assert np.percentile(err_cmd, 95) < 8.0  # a half period spans frame-to-frame steps
    # it really moves over the whole range
    assert f[keep].min() < 70 and f[keep].max() > 170


def _slope_bound(a_carrier, f_max, a_detent):
    edge_n = KNOB_DEFAULTS["detent_edge_ms"] * FS / 1000
    return (a_carrier + a_detent) * np.pi / (2 * edge_n) + 2 * np.pi * f_max * a_carrier / FS


@pytest.mark.parametrize("condition", ["HD+CF", "HD+VF", "HD+BF", "VD+VF"])
def test_no_discontinuity_and_ramped_start_and_stop(condition):
    _, _, frames = scenario(2)
    r = run_pipeline(frames, condition, sectors=SECTORS)
    for v, a_c, a_d, f_max in (
        (r.screen_v, 50.0, 50.0 if condition.startswith("HD") else 0.0, 180.0),
        (r.piezo_v, KNOB_DEFAULTS["vd_peak_v"], 0.0, KNOB_DEFAULTS["vd_freq_hz"]),
    ):
        assert np.all(np.isfinite(v))
        assert np.max(np.abs(np.diff(v))) <= _slope_bound(a_c, f_max, a_d)
        ramp = int(0.002 * FS)
        assert np.abs(v[:ramp]).max() < 0.1 * max(a_c, 1.0)
        assert np.abs(v[-ramp:]).max() < 0.1 * max(a_c, 1.0)
    assert np.abs(r.screen_v).max() <= 100.0  # within screen_max_vpp = 200


def test_vibrotactile_detents_start_within_one_block():
    _, _, frames = scenario(3)
    r = run_pipeline(frames, "VD+VF", sectors=SECTORS)
    on = np.abs(r.piezo_v) > 1e-9
    for c in r.crossings:
        k = int(np.ceil(c.t_s * FS))
        assert on[k : k + B].any()


def test_zero_crossing_frequency_estimate_against_a_chirp_and_hilbert():
    from scipy.signal import hilbert

    t = np.arange(int(1.0 * FS)) / FS
    f_t = 60.0 + 120.0 * t  # linear chirp 60 -> 180 Hz
    x = np.sin(2 * np.pi * (60.0 * t + 60.0 * t**2))
    tz, f = instantaneous_freq_hz(x, FS)
    assert np.max(np.abs(f - np.interp(tz, t, f_t))) < 0.2
    # second method: the phase slope of the analytic signal
    ph = np.unwrap(np.angle(hilbert(x)))
    f_h = np.gradient(ph, t) / (2 * np.pi)
    mid = slice(2000, -2000)
    assert np.median(np.abs(f_h[mid] - f_t[mid])) < 0.2
