"""The closed-loop plate model against independent references.

- steady state of a long sine = the twin's FRF (frequency domain, another code path),
  amplitude AND phase;
- the per-mode FOH recursion = scipy.signal.lsim on the full modal state space;
- free decay after the drive stops = exp(-zeta omega_1 t) (analytic);
- a disconnected patch exerts nothing; PALL = PA + PB + PC + PD (superposition);
- window RMS and tone through the coordinates' covariance = direct computation.
"""

from __future__ import annotations

import numpy as np
import pytest

from plugins.twin.plate import closed_loop as cl
from plugins.twin.plate.model import build_twin, default_params

FS = 48000.0
PTS = np.array([[401.73, 223.645], [461.73, 223.645], [100.0, 100.0], [700.0, 400.0]])


@pytest.fixture(scope="module")
def twin():
    return build_twin(default_params())


def ramped_sine(f_hz, amp_v, dur_s, ramp_s=0.1, fs=FS):
    t = np.arange(int(round(dur_s * fs))) / fs
    return amp_v * np.minimum(1.0, t / ramp_s) * np.sin(2 * np.pi * f_hz * t), t


@pytest.mark.parametrize(("f_hz", "exc"), [(163.0, "PALL"), (465.0, "PA"), (607.2, "PB")])
def test_steady_state_is_the_twin_frf_with_its_phase(twin, f_hz, exc):
    v, t = ramped_sine(f_hz, 50.0, 3.0)
    x = cl.displacement_at(twin, v, [(0, v.size, {exc})], PTS, FS)
    tail = slice(-int(0.5 * FS), None)
    basis = np.column_stack(
        [np.cos(2 * np.pi * f_hz * t[tail]), np.sin(2 * np.pi * f_hz * t[tail])]
    )
    ab = np.linalg.lstsq(basis, x[:, tail].T, rcond=None)[0]  # x = a cos + b sin
    # drive 50 sin(wt) = Re(-50j e^{jwt}) -> x = Re(H (-50j) e^{jwt}) = a cos + b sin
    phasor = ab[0] - 1j * ab[1]
    h = twin.frf_um_per_v(PTS[:, 0], PTS[:, 1], [f_hz], (exc,))[0, :, 0]
    assert np.abs(phasor - h * (-50j)).max() < 2e-3 * np.abs(h * 50).max()


def test_foh_recursion_matches_lsim_on_the_full_modal_state_space(twin):
    from scipy.signal import lsim

    v, t = ramped_sine(428.0, 40.0, 0.08, ramp_s=0.01)
    v[: int(0.005 * FS)] = 0.0
    v[int(0.005 * FS) :] += 5.0 * np.sign(np.sin(2 * np.pi * 97 * t[int(0.005 * FS) :]))  # edges
    w = cl.weights_from_spans([(0, v.size, {"PA", "PC"})], v.size)
    coords = cl.modal_coordinates(twin, v, w, FS)
    om, z = twin.modes.omega_rad_s, twin.params.damping_ratio
    r = om.size
    a = np.zeros((2 * r, 2 * r))
    a[:r, r:] = np.eye(r)
    a[r:, :r] = -np.diag(om**2)
    a[r:, r:] = -np.diag(2 * z * om)
    b = np.zeros((2 * r, 1))
    b[r:, 0] = twin.q[:, 0] + twin.q[:, 2]
    _, y, _ = lsim((a, b, np.eye(2 * r)[:r], np.zeros((r, 1))), v, t)
    assert np.abs(y.T - coords[:r]).max() < 1e-5 * np.abs(y).max()


def test_free_decay_after_the_drive_stops_is_exp_minus_zeta_omega_t(twin):
    f1 = float(twin.freq_hz[0])
    v, _ = ramped_sine(f1, 20.0, 1.5, ramp_s=0.05)
    v = np.concatenate(
        [v * np.minimum(1, (v.size - np.arange(v.size)) / 480), np.zeros(int(2 * FS))]
    )
    x = cl.displacement_at(twin, v, [(0, v.size, {"PALL"})], [(371.73, 223.645)], FS)[0]
    t = np.arange(x.size) / FS
    seg = t >= 2.0  # drive off at 1.5 s; higher modes are gone after 0.5 s
    env = np.abs(x[seg])
    # peak envelope per period of mode 1, fit log-linear
    per = int(FS / f1)
    n = env.size // per
    peaks = env[: n * per].reshape(n, per).max(axis=1)
    tk = t[seg][: n * per].reshape(n, per)[np.arange(n), env[: n * per].reshape(n, per).argmax(1)]
    slope = np.polyfit(tk, np.log(peaks), 1)[0]
    expect = twin.params.damping_ratio * 2 * np.pi * f1
    assert slope == pytest.approx(-expect, rel=0.03)


def test_open_relays_or_silence_give_no_motion_and_pall_is_the_sum(twin):
    v, _ = ramped_sine(300.0, 50.0, 0.3)
    n = v.size
    assert not np.any(cl.displacement_at(twin, v, np.zeros((n, 4)), PTS, FS))
    assert not np.any(cl.displacement_at(twin, np.zeros(n), [(0, n, {"PALL"})], PTS, FS))
    x_all = cl.displacement_at(twin, v, [(0, n, {"PALL"})], PTS, FS)
    x_sum = sum(cl.displacement_at(twin, v, [(0, n, {p})], PTS, FS) for p in cl.PATCHES)
    assert np.abs(x_all - x_sum).max() < 1e-9 * np.abs(x_all).max()


def test_patch_switched_off_mid_part_leaves_the_plate_ringing_freely(twin):
    """A relay that opens (in silence) stops the forcing, not the motion."""
    v, _ = ramped_sine(163.0, 50.0, 0.6)
    v[v.size // 2 :] = 0.0
    w = cl.weights_from_spans([(0, v.size // 2, {"PB"})], v.size)
    x = cl.displacement_at(twin, v, w, PTS[:1], FS)[0]
    after = x[v.size // 2 : v.size // 2 + int(0.02 * FS)]
    assert np.abs(after).max() > 0.3 * np.abs(x[: v.size // 2]).max()


def test_relay_log_gives_the_same_weights_as_the_spans():
    from types import SimpleNamespace as R

    chans = {"PA": 1, "PB": 2, "PC": 3, "PD": 4}
    log = [
        R(clock=100, channel=1, closed=True),
        R(clock=100, channel=5, closed=True),  # screen: not a patch
        R(clock=500, channel=2, closed=True),
        R(clock=500, channel=1, closed=False),
        R(clock=900, channel=2, closed=False),
    ]
    spans = [(100, 500, {"PA"}), (500, 900, {"PB"})]
    for start in (0, 50, 300):
        w_log = cl.weights_from_relay_log(log, chans, 1000 - start, start)
        w_spans = cl.weights_from_spans(spans, 1000)[start:]
        assert np.array_equal(w_log, w_spans)
    rec = np.zeros((1000, 2))
    rec[:, 0] = np.arange(1000)
    v, w = cl.drive_from_recording(rec[200:], log, chans, start=300, stop=700, clock0=200)
    assert v[0] == 300 and v.size == 400 and w[199, 0] == 1 and w[200, 1] == 1


def test_window_rms_and_tone_through_the_covariance_match_direct(twin):
    v, t = ramped_sine(221.8, 30.0, 1.0)
    v += 0.3 * np.sin(2 * np.pi * 53 * t)
    w = cl.weights_from_spans([(0, v.size, {"PC"})], v.size)
    coords = cl.modal_coordinates(twin, v, w, FS)
    xs, ys = cl.hand_subgrid_mm((580.0, 150.0), subgrid=4)
    gx, gy = np.meshgrid(xs, ys)
    pts = np.column_stack([gx.ravel(), gy.ravel()])
    shapes = cl.lattice_shapes_um(twin, xs, ys)
    assert np.allclose(
        shapes, cl.point_shapes_um(twin, pts), rtol=0, atol=1e-9 * np.abs(shapes).max()
    )
    x = shapes @ coords
    win = (int(0.4 * FS), int(0.9 * FS))
    rms = np.sqrt(np.mean(x[:, win[0] : win[1]] ** 2, axis=1))
    assert np.allclose(cl.window_rms_um(shapes, coords, win), rms, rtol=1e-9)
    tone = cl.window_tone_um(shapes, coords, win, 221.8, FS)
    tt = t[win[0] : win[1]]
    basis = np.column_stack([np.cos(2 * np.pi * 221.8 * tt), np.sin(2 * np.pi * 221.8 * tt)])
    ab = np.linalg.lstsq(basis, x[:, win[0] : win[1]].T, rcond=None)[0]
    assert np.allclose(tone, np.hypot(*ab), rtol=1e-9)
    assert np.all(tone < np.sqrt(2) * rms * 1.001)  # the 53 Hz component is rejected


def test_square_levels_take_the_value_half_the_points_reach():
    amp = np.zeros((6, 6))  # 3 x 3 squares of 2 x 2 points, rows y
    amp[0:2, 0:2] = [[1, 2], [3, 4]]  # square (0, 0): 2nd largest of 4 = 3
    amp[4:6, 2:4] = [[9, 0], [0, 0]]  # square (2, 1): one point high -> 0
    lv = cl.square_levels_um(amp.ravel(), squares=3, subgrid=2)
    assert lv[0, 0] == 3 and lv[2, 1] == 0 and lv.shape == (3, 3)


def test_twin_vibrometer_is_registered_and_reports_progress(loop_plugins, loop_profile):
    from plugins.twin.plate.vibrometer import SweepSettings, TwinVibrometer

    assert loop_profile.get("vibrometer.driver") == "twin"
    reg = loop_plugins.get("vibrometer", "twin")
    status = reg.probe(loop_profile)
    assert (status.kind, status.name, status.state) == ("vibrometer", "twin", "simulated")
    assert isinstance(reg.factory(loop_profile), TwinVibrometer)
    coarse = SweepSettings(
        f_stop_hz=200.0, sweep_s=1.0, record_s=3.0, sample_rate_hz=512.0, sweeps=2
    )
    calls = []
    out = TwinVibrometer(loop_profile, coarse).measure(progress=lambda d, n: calls.append((d, n)))
    assert calls == [(k, 7) for k in range(1, 8)]  # 5 excitations, then 2 sweeps
    from console.files.vibration_map import make_map

    m = make_map(**{k: v for k, v in out.items() if k != "meta"})
    assert m.frf_um_per_v.shape == (5, 84, out["freq_hz"].size)
