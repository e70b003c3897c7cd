"""The sensor's mass cancelled with a clip-on dummy, and the knee-shaped chirp.

Reference, independent of the cancellation: a 2-DOF oscillator whose loaded receptance is
solved directly with the point mass in its mass matrix, (K - w^2 (M + m e_j e_j^T) + i w C)^-1.
"""

from __future__ import annotations

import math

import numpy as np
import pytest
from scipy import signal

from console.plugin_api import UserError
from plugins.vibrotactile.mass_cancel import cancel, cancel_coherence, noise_gain
from plugins.vibrotactile.roving import RovingSettings, chirp_v, h1

F_HZ = np.arange(20.0, 200.0, 0.05)
M_KG = np.diag([0.40, 0.25])
K_N_M = np.array([[3.0e5, -1.0e5], [-1.0e5, 1.6e5]])
C_NS_M = 2e-5 * K_N_M + 0.5 * M_KG  # proportional damping: ~1 % near the modes


def _receptance(mass_at_j_kg: float, i: int, j: int) -> np.ndarray:
    """H_ij (m/N) with a point mass on DOF j, solved directly per frequency."""
    w = 2 * math.pi * F_HZ
    m = M_KG.copy()
    m[j, j] += mass_at_j_kg
    dyn = K_N_M[None] - w[:, None, None] ** 2 * m[None] + 1j * w[:, None, None] * C_NS_M[None]
    return np.linalg.inv(dyn)[:, i, j]


def _db(a, b):
    return np.abs(20 * np.log10(np.abs(a) / np.abs(b)))


@pytest.mark.parametrize("dummy_g", [10.0, 20.0, 35.0])
@pytest.mark.parametrize(("i", "j"), [(0, 1), (1, 1), (1, 0)])
def test_two_passes_give_the_mass_free_frf_exactly(dummy_g, i, j):
    sensor_g = 10.0
    true = _receptance(0.0, i, j)
    with_sensor = _receptance(sensor_g / 1e3, i, j)
    with_dummy = _receptance((sensor_g + dummy_g) / 1e3, i, j)
    assert _db(with_sensor, true).max() > 3.0  # the sensor's mass moves the peaks
    got = cancel(with_sensor, with_dummy, sensor_g, dummy_g)
    assert _db(got, true).max() < 1e-6
    assert np.allclose(got, true, rtol=1e-8, atol=0)
    # the wrong sensor mass stated leaves an error (the method can fail)
    wrong = cancel(with_sensor, with_dummy, 0.5 * sensor_g, dummy_g)
    assert _db(wrong, true).max() > 1.0


def test_a_heavier_dummy_costs_less_noise_as_predicted():
    rng = np.random.default_rng(3)
    n, rel = 4000, 0.01  # 1 % complex noise on each pass, at a bin the mass barely moves
    h = np.full(n, 1.0 + 0.5j)
    spread = {}
    for dummy_g in (7.0, 14.0):
        e1 = rel * (rng.standard_normal(n) + 1j * rng.standard_normal(n)) / math.sqrt(2)
        e2 = rel * (rng.standard_normal(n) + 1j * rng.standard_normal(n)) / math.sqrt(2)
        got = cancel(h * (1 + e1), h * (1 + e2), 7.0, dummy_g)
        spread[dummy_g] = float(np.sqrt(np.mean(np.abs(got / h - 1) ** 2)))  # rms
        predicted = noise_gain(7.0, dummy_g) * rel
        assert spread[dummy_g] == pytest.approx(predicted, rel=0.1)
    assert spread[14.0] < 0.8 * spread[7.0]


def test_masked_bins_stay_masked_and_coherence_is_the_worse_pass():
    h1_, h2_ = np.array([0.0, 1.0, 2.0]), np.array([1.0, 0.0, 2.0])
    assert np.array_equal(cancel(h1_, h2_, 7.0, 7.0)[:2], [0.0, 0.0])
    assert cancel(h1_, h2_, 7.0, 7.0)[2] == pytest.approx(2.0)
    assert np.array_equal(cancel_coherence([0.95, 0.5], [0.8, 0.99]), [0.8, 0.5])


@pytest.mark.parametrize(
    ("sensor_g", "dummy_g", "word"),
    [(None, 7.0, "--sensor-mass-g"), (7.0, 0.0, "--dummy-mass-g 0"), (7.0, -3.0, "--dummy")],
)
def test_bad_masses_get_one_line_naming_the_option(sensor_g, dummy_g, word):
    with pytest.raises(UserError, match=word):
        cancel(np.ones(3), np.ones(3), sensor_g, dummy_g)


def test_the_knee_chirp_falls_as_knee_over_f_and_h1_stays_exact():
    fs = 8000
    s = RovingSettings(level_v=90.0, knee_hz=200.0, f_start_hz=20, f_stop_hz=1500, sweep_s=0.5)
    x = chirp_v(s, fs)
    env = np.abs(signal.hilbert(x))
    t = np.arange(x.size) / fs
    f_t = s.f_start_hz * (s.f_stop_hz / s.f_start_hz) ** (t / s.sweep_s)
    for f_hz, want_v in ((100.0, 90.0), (400.0, 45.0), (800.0, 22.5)):
        k = int(np.argmin(np.abs(f_t - f_hz)))
        assert env[k] == pytest.approx(want_v, rel=0.08)  # the Hilbert envelope ripples
    x = np.concatenate([x, np.zeros(400)])
    b = signal.firwin(31, 900, fs=fs)
    y = np.convolve(x, b)[: x.size]
    f, h, _ = h1(x, y, fs)
    _, ref = signal.freqz(b, worN=f, fs=fs)
    band = (f >= 50) & (f <= 800)
    assert _db(h[band], ref[band]).max() < 0.1
    with pytest.raises(UserError, match="knee_hz"):
        RovingSettings(knee_hz=-1.0).check()


def test_a_roving_run_with_a_dummy_asks_for_it_and_writes_the_mass_free_map(tmp_path, monkeypatch):
    """The run's guide (a fake instrument: the 2-DOF oscillator, the sensor on DOF j)."""
    # lazy: the run module only for this test
    import plugins.vibrotactile.roving_run as rr
    from console.plugin_api import EXCITATIONS, load_map

    state = {"mass_g": 0.0, "j": 0}
    asked = []

    def fake_measure(outputs, s, excitations, delay_default=0.0):
        j = state["j"]
        frf = np.stack([(1 + e) * _receptance(state["mass_g"] / 1e3, e % 2, j) for e in range(5)])
        return {"freqs_hz": F_HZ, "frf": frf, "coherence": np.ones(frf.shape), "delay_samples": 0}

    def place(point, x_mm, y_mm):
        state.update(j=point - 1, mass_g=7.0)

    def dummy(point, x_mm, y_mm, on):
        asked.append((point, on))
        state["mass_g"] = 7.0 + (14.0 if on else 0.0)

    monkeypatch.setattr(rr, "measure_point", fake_measure)
    s = RovingSettings(band_hz=(20.0, 199.0), f_stop_hz=700.0)
    run = rr.RovingRun(
        None,
        tmp_path / "m.npz",
        np.array([[100.0, 100.0], [160.0, 100.0]]),
        s,
        sensor={"kind": "accelerometer", "mass_g": 7.0},
        dummy_mass_g=14.0,
    )
    run.run(place, dummy=dummy)
    assert asked == [(1, True), (1, False), (2, True), (2, False)]
    m = load_map(tmp_path / "m.npz", require_all=False)
    for j in range(2):
        true = np.stack([(1 + e) * _receptance(0.0, e % 2, j) for e in range(5)])
        loaded = np.stack([(1 + e) * _receptance(0.007, e % 2, j) for e in range(5)])
        assert _db(loaded, true).max() > 2.0  # what the 7 g would leave in the map
        assert _db(m.frf_um_per_v[:, j], true).max() < 1e-6
    assert list(m.excitations) == list(EXCITATIONS)
    with pytest.raises(UserError, match="--sensor-mass-g"):
        rr.RovingRun(None, tmp_path / "n.npz", np.zeros((1, 2)), s, sensor={}, dummy_mass_g=7.0)


def test_the_cancelled_coherence_carries_both_passes_noise_and_falls_where_it_divides():
    """Two passes of coherence 0.99 each: the cancellation multiplies their noise
    (``noise_gain``) where the mass hardly matters, and much more where H1 and H2 nearly
    cancel in the line's denominator."""
    h_far = np.array([1.0 + 0.0j])
    c = cancel_coherence([0.99], [0.99], h_far, h_far, 7.0, 14.0)[0]
    q_pass = 0.01 / 0.99
    assert (1 - c) / c == pytest.approx(noise_gain(7.0, 14.0) ** 2 * q_pass, rel=1e-6)
    # H2 = 3 H1 with r = 1/2: den = 1.5 * 3 - 0.5 = 4, H = 3/4 H1 ... and H2 close to
    # r/(1+r) H1 makes den small: H grows and so does its error
    h1_ = np.array([1.0 + 0.0j])
    near = cancel_coherence([0.99], [0.99], h1_, np.array([0.36 + 0.0j]), 7.0, 14.0)[0]
    assert near < 0.5 < c
