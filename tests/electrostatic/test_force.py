"""Electrostatic force (Eqs. 1-2), skin permittivity model, detection thresholds."""

import numpy as np
import pytest

from plugins.electrostatic.force import (
    DEFAULTS,
    EPS0_F_PER_M,
    Material,
    attraction_force_n,
    below_threshold,
    expected_force,
    force_per_v2,
    friction_n,
    skin_eps_r,
    threshold_check,
    threshold_vpp,
)


def test_equal_permittivities_reduce_to_parallel_plate_force():
    # independent reference: F = eps0 eps_r A V^2 / (2 d^2) for one dielectric of thickness d
    a, t1, t2, eps, v = 1e-4, 1e-6, 50e-6, 7.0, 80.0
    d = t1 + t2
    expected = EPS0_F_PER_M * eps * a * v**2 / (2 * d**2)
    got = force_per_v2(a, t1, eps, t2, eps) * v**2
    assert got == pytest.approx(expected, rel=1e-12)


def test_force_matches_energy_derivative_of_the_capacitor():
    # second method: F = 1/2 V^2 dC/dd with C = eps0 eps_r A / d (numerical derivative)
    a, eps, v, d = 2e-4, 3.0, 100.0, 30e-6
    c = lambda dd: EPS0_F_PER_M * eps * a / dd  # noqa: E731
    h = d * 1e-6
    f_energy = 0.5 * v**2 * abs(c(d + h) - c(d - h)) / (2 * h)
    assert force_per_v2(a, d / 2, eps, d / 2, eps) * v**2 == pytest.approx(f_energy, rel=1e-6)


def test_time_average_of_instantaneous_force_equals_rms_force():
    m = Material.from_settings()
    fs, f = 48000, 180.0
    t = np.arange(fs) / fs  # 1 s = 180 whole periods
    v = 50.0 * np.sin(2 * np.pi * f * t)
    inst = attraction_force_n(v, f, m)
    ef = expected_force(v, fs, m)
    assert ef["freq_hz"] == pytest.approx(f, abs=1.0)
    assert inst.mean() == pytest.approx(ef["force_mean_n"], rel=1e-6)
    assert ef["force_peak_n"] == pytest.approx(
        2 * ef["force_mean_n"], rel=1e-3
    )  # sine: Vp^2 = 2 Vrms^2
    # the force of a sine pulses at twice its frequency
    spec = np.abs(np.fft.rfft(inst - inst.mean()))
    assert np.argmax(spec) == pytest.approx(2 * f, abs=1)


def test_paper_knob_signal_gives_a_small_force_in_the_millinewton_range():
    m = Material.from_settings()
    f = float(attraction_force_n(50.0 / np.sqrt(2), 180.0, m))
    assert 1e-4 < f < 0.05  # "too small to be perceived by a stationary finger"
    # Eq. 2: friction grows by mu * f_e
    assert float(friction_n(f, m) - friction_n(0.0, m)) == pytest.approx(m.mu * f)


def test_skin_permittivity_falls_with_frequency_to_its_floor():
    m = Material.from_settings()
    eps = skin_eps_r(np.array([10.0, 100.0, 1000.0, 1e9]), m)
    assert eps[1] == pytest.approx(DEFAULTS["skin_eps_r_ref"])
    assert np.all(np.diff(eps) <= 0)
    assert eps[-1] == pytest.approx(DEFAULTS["skin_eps_r_min"])
    assert np.isfinite(skin_eps_r(0.0, m))  # DC is clamped, not infinite
    # so the same voltage pulls less at high frequency
    assert attraction_force_n(50.0, 1000.0, m) < attraction_force_n(50.0, 60.0, m)


def test_threshold_curve_is_u_shaped_with_minimum_near_80_hz():
    f = np.geomspace(15, 1920, 400)
    th = threshold_vpp(f, DEFAULTS["threshold_freq_hz"], DEFAULTS["threshold_vpp"])
    assert 60 <= f[np.argmin(th)] <= 100
    assert th[0] > th.min() and th[-1] > th.min()
    assert 10 < th.min() < 100  # tens of volts


def test_threshold_interpolates_in_db_over_log_frequency_and_holds_ends():
    fx, ty = [100.0, 400.0], [20.0, 80.0]
    assert threshold_vpp(200.0, fx, ty) == pytest.approx(40.0)  # geometric midpoint
    assert threshold_vpp(10.0, fx, ty) == pytest.approx(20.0)
    assert threshold_vpp(5000.0, fx, ty) == pytest.approx(80.0)
    with pytest.raises(ValueError):
        threshold_vpp(100.0, [400.0, 100.0], ty)


def test_below_threshold_flags_weak_settings_and_squares_win_at_low_frequency():
    assert below_threshold(15.0, 80.0)
    assert not below_threshold(100.0, 180.0)
    r = threshold_check(35.0, 30.0, waveform="square")
    s = threshold_check(35.0, 30.0, waveform="sine")
    assert r["threshold_vpp"] < s["threshold_vpp"]
    assert not r["below"] and s["below"]
    assert threshold_check(0.0, 80.0)["below"]
