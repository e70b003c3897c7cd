"""Simulated laser-vibrometer measurement vs the twin's exact FRF."""

from __future__ import annotations

import warnings
from dataclasses import replace

import numpy as np
import pytest

from plugins.twin.plate.model import build_twin, default_params, grid_points_mm
from plugins.twin.plate.vibrometer import (
    SweepSettings,
    linear_sweep,
    measure,
    noise_std_um_per_v,
)


@pytest.fixture(scope="module")
def sim():
    return build_twin(default_params())


@pytest.fixture(scope="module")
def grid_measurement(sim):
    x, y = grid_points_mm()
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        return measure(sim, x, y)


def z_scores(result, twin, settings, band=None):
    """|measured - exact| / predicted noise std on valid bins (complex Gaussian: E z^2 = 1)."""
    f, v = result["freqs_hz"], result["valid"].copy()
    if band is not None:
        v &= (f >= band[0]) & (f <= band[1])
    exact = twin.frf_um_per_v(result["x_mm"], result["y_mm"], f, result["excitations"])
    std = noise_std_um_per_v(linear_sweep(settings), f, settings)
    return np.abs(result["frf"][..., v] - exact[..., v]) / std[v]


def test_measurement_arrays_and_metadata(grid_measurement):
    r = grid_measurement
    f = r["freqs_hz"]
    assert r["frf"].shape == (5, 84, f.size) and np.iscomplexobj(r["frf"])
    assert r["valid"].dtype == bool and r["valid"].shape == f.shape
    assert f[0] == 0.0 and f[-1] <= 625.0 and np.all(np.diff(f) > 0)
    assert r["excitations"] == ("PA", "PB", "PC", "PD", "PALL")
    assert r["meta"]["units"] == "um/V" and r["meta"]["quantity"] == "displacement"
    assert r["meta"]["settings"]["amplifier_gain"] == 50.0
    assert r["meta"]["ringdown_left"] < 1e-3


def test_near_dc_bins_are_masked_and_never_win_an_argmax(grid_measurement):
    r = grid_measurement
    f, valid = r["freqs_hz"], r["valid"]
    assert not valid[f < 5.0].any() and valid[(f >= 5.0) & (f < 620)].all()
    assert np.isnan(r["frf"][..., ~valid]).all()
    mag = np.abs(r["frf"])
    best = np.nanargmax(mag.reshape(-1, f.size), axis=1)
    assert valid[best].all()


def test_measured_frf_matches_the_model_within_the_noise(sim, grid_measurement):
    z = z_scores(grid_measurement, sim, SweepSettings())
    # H1 over 3 sweeps with output noise: complex error with variance sigma^2 / (3 |X|^2)
    assert 0.9 < np.mean(z**2) < 1.1
    assert np.percentile(z, 99.9) < 4.0
    # and in plain terms: within a few % of the largest response everywhere valid
    r = grid_measurement
    exact = sim.frf_um_per_v(r["x_mm"], r["y_mm"], r["freqs_hz"][r["valid"]])
    err = np.abs(r["frf"][..., r["valid"]] - exact)
    assert err.max() < 0.1 * np.abs(exact).max()


def test_two_modes_closer_than_their_bandwidth_are_measured_unbiased(sim, grid_measurement):
    fn = sim.freq_hz
    gaps = np.diff(fn) < 0.02 * fn[:-1]  # closer than the half-power bandwidth 2 zeta f
    i = int(np.flatnonzero(gaps & (fn[:-1] < 600))[0])
    band = (fn[i] - 5 * 0.01 * fn[i], fn[i + 1] + 5 * 0.01 * fn[i + 1])
    z = z_scores(grid_measurement, sim, SweepSettings(), band)
    assert 0.7 < np.mean(z**2) < 1.4


def test_frf_is_per_volt_at_the_piezo_whatever_the_gain(sim):
    x, y = np.array([101.73, 461.73]), np.array([163.645, 343.645])
    s = SweepSettings(amplifier_gain=10.0, record_s=6.0, sweep_s=4.0, seed=3)
    z = z_scores(measure(sim, x, y, s), sim, s)
    assert 0.8 < np.mean(z**2) < 1.25


def test_light_damping_needs_a_longer_record(sim):
    light = build_twin(replace(sim.params, damping_ratio=0.001))
    x, y = np.array([101.73]), np.array([163.645])
    short = SweepSettings(sweep_s=4.0, record_s=6.0, seed=1)
    long_ = SweepSettings(sweep_s=4.0, record_s=24.0, seed=1)
    r_short = measure(light, x, y, short, ("PA",))
    r_long = measure(light, x, y, long_, ("PA",))
    assert r_short["meta"]["ringdown_left"] > 0.1 > 1e-3 > r_long["meta"]["ringdown_left"]
    assert np.mean(z_scores(r_long, light, long_) ** 2) < 1.3
    assert z_scores(r_short, light, short).max() > 20.0  # ring-down cut off: leakage bias
    assert z_scores(r_long, light, long_).max() < 5.0


def test_point_on_a_nodal_line_is_measured_without_blowing_up(sim):
    a_mm = sim.params.plate.a_m * 1e3
    x, y = np.array([a_mm / 2, a_mm / 4]), np.array([200.0, 200.0])
    s = SweepSettings(record_s=6.0, sweep_s=4.0, seed=5)
    r = measure(sim, x, y, s, ("PA",))
    f2 = sim.freq_hz[1]  # antisymmetric in x: x = a/2 is on its nodal line
    k = np.argmin(np.abs(r["freqs_hz"] - f2))
    assert np.all(np.isfinite(r["frf"][..., r["valid"]]))
    assert r["coherence"][0, 0, k] < r["coherence"][0, 1, k]
    assert np.mean(z_scores(r, sim, s) ** 2) < 1.3


def test_grid_measurement_saves_as_a_vibration_map(tmp_path, plugins):
    from console.config.profile import load_profile
    from console.files.vibration_map import load_map, make_map, save_map
    from plugins.twin.plate.vibrometer import measure_grid, settings_from_profile

    profile = load_profile("sim", plugins)
    s = settings_from_profile(profile, sweep_s=2.0, record_s=3.0)
    assert s.amplifier_gain == profile.get("amplifiers.piezo_gain")
    out = measure_grid(profile, s)
    m = make_map(**{k: v for k, v in out.items() if k != "meta"})
    back = load_map(save_map(tmp_path / "twin.npz", m))
    assert back.frf_um_per_v.shape == (5, 84, back.freq_hz.size)
    assert back.masked[back.freq_hz < 5.0].all() and not back.masked[back.freq_hz > 6].any()
    assert np.all(back.frf_um_per_v[:, :, back.masked] == 0)
    np.testing.assert_allclose(back.points_mm[50], [41.73 + 2 * 60, 43.645 + 4 * 60])


def test_fft_synthesis_matches_time_stepped_state_space(sim):
    """The response synthesis equals a modal state space stepped through the sweep."""
    from scipy import signal

    from plugins.twin.plate.vibrometer import velocity_response

    s = SweepSettings(sweep_s=0.5, record_s=1.0)
    u = linear_sweep(s) * s.amplifier_gain
    x, y = np.array([101.73]), np.array([163.645])
    v_fft = velocity_response(sim, x, y, u, s.sample_rate_hz)[0, 0]  # PA
    # independent: state space of the kept modes + the static residual as a feedthrough
    w, z, q = sim.modes.omega_rad_s, sim.params.damping_ratio, sim.q[:, 0]
    phi = sim.modes.shapes(x / 1e3, y / 1e3)[0]
    r = w.size
    a = np.block([[np.zeros((r, r)), np.eye(r)], [-np.diag(w**2), -np.diag(2 * z * w)]])
    b = np.concatenate([np.zeros(r), q])[:, None]
    k = 16  # the continuous sweep, sampled 16x finer (first-order hold)
    fine = replace(s, sample_rate_hz=s.sample_rate_hz * k)
    u_fine = linear_sweep(fine) * s.amplifier_gain
    t_fine = np.arange(u_fine.size) / fine.sample_rate_hz
    # velocity = C_v x (modal velocities) + residual * du/dt
    c = np.concatenate([np.zeros(r), phi])[None, :]
    _, v_ss, _ = signal.lsim((a, b, c, np.zeros((1, 1))), u_fine, t_fine, interp=True)
    res_um = sim.frf_um_per_v(x, y, [0.0], ("PA",))[0, 0, 0] * 1e-6
    res_static = res_um - phi @ (q / w**2)  # the residual part of the static response
    v_ss = v_ss + res_static.real * np.gradient(u_fine, t_fine)
    err = np.abs(v_ss[::k] - v_fft).max() / np.abs(v_fft).max()
    assert err < 3e-3, err
