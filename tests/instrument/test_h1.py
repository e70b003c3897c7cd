"""H1, coherence, the loopback delay and acceleration -> displacement on analytic cases."""

from __future__ import annotations

import math

import numpy as np
from scipy import signal

from plugins.vibrotactile.roving import (
    RovingSettings,
    chirp_v,
    delay_samples,
    displacement_um_per_v,
    h1,
)

FS = 8000


def _fir() -> np.ndarray:
    """A known linear system: a 31-tap low-pass FIR (its exact response by freqz)."""
    return signal.firwin(31, 900, fs=FS)


def test_h1_of_a_known_fir_is_exact_and_fully_coherent_without_noise():
    s = RovingSettings(level_v=5.0, f_start_hz=20, f_stop_hz=1500, sweep_s=0.5, tail_s=0.05)
    x = np.concatenate([chirp_v(s, FS), np.zeros(int(s.tail_s * FS))])
    b = _fir()
    y = np.convolve(x, b)[: x.size]  # the FIR's tail fits in the silence after the chirp
    f, h, coh = h1(np.stack([x, x]), np.stack([y, y]), FS)
    _, ref = signal.freqz(b, worN=f, fs=FS)
    band = (f >= 50) & (f <= 800)
    err_db = 20 * np.log10(np.abs(h[band]) / np.abs(ref[band]))
    assert np.max(np.abs(err_db)) < 0.1
    assert np.max(np.abs(np.angle(h[band] / ref[band]))) < 0.01
    assert np.min(coh[band]) > 0.999


def test_noise_lowers_the_coherence_where_the_output_is_weak():
    s = RovingSettings(level_v=5.0, f_start_hz=20, f_stop_hz=1500, sweep_s=0.5, tail_s=0.05)
    x = np.concatenate([chirp_v(s, FS), np.zeros(int(s.tail_s * FS))])
    y = np.convolve(x, _fir())[: x.size]
    rng = np.random.default_rng(1)
    ys = y + 0.05 * rng.standard_normal((4, x.size))
    f, _, coh = h1(np.broadcast_to(x, ys.shape), ys, FS)
    passband = (f > 100) & (f < 700)
    stopband = (f > 1300) & (f < 1450)  # the FIR's stop band: output ~ noise only
    assert np.median(coh[passband]) > 0.95
    assert np.median(coh[stopband]) < 0.6


def test_the_loopback_delay_is_found_to_a_fraction_of_a_sample():
    s = RovingSettings(level_v=1.0, f_start_hz=20, f_stop_hz=3000, sweep_s=0.3, tail_s=0.02)
    x = np.concatenate([chirp_v(s, FS), np.zeros(200)])
    for lag in (0, 37, 45.5):
        # a fractional lag as an ideal band-limited delay (a phase ramp)
        n = x.size
        xf = np.fft.rfft(x)
        y = np.fft.irfft(xf * np.exp(-2j * math.pi * np.fft.rfftfreq(n) * lag), n)
        assert abs(delay_samples(x, y) - lag) < 0.1


def test_acceleration_becomes_displacement_and_low_bins_are_masked():
    f = np.array([0.0, 5.0, 50.0, 500.0])
    w = 2 * math.pi * f
    disp_m = np.array([1e-6, 2e-6, 3e-6, 4e-6]) * (1 + 0.5j)
    acc = -(w**2) * disp_m
    d, masked = displacement_um_per_v(f, acc * np.exp(-1j * w * 1e-3), 1e-3, 10.0)
    assert masked.tolist() == [True, True, False, False]
    assert np.all(d[masked] == 0)
    assert np.allclose(d[~masked], disp_m[~masked] * 1e6)


def _resonant_case(repeats: int, seed: int):
    """A lightly damped resonance with an antiresonance-like dip (a known IIR), its
    chirp response plus white sensor noise: (freqs, H, coherence, truth, true coherence)."""
    s = RovingSettings(level_v=5.0, f_start_hz=20, f_stop_hz=1500, sweep_s=0.6, tail_s=0.4)
    x = np.concatenate([chirp_v(s, FS), np.zeros(int(s.tail_s * FS))])
    b, a = signal.iirpeak(400, 40, fs=FS)  # a resonance; far from it the response is small
    y = signal.lfilter(b, a, x)
    sigma = 0.02
    rng = np.random.default_rng(seed)
    ys = y + sigma * rng.standard_normal((repeats, x.size))
    xs = np.broadcast_to(x, ys.shape)
    f, h, coh = h1(xs, ys, FS, smooth_bins=8)
    _, classic = h1(xs, ys, FS)[1:]
    _, ref = signal.freqz(b, a, worN=f, fs=FS)
    sig = np.abs(np.fft.rfft(y)) ** 2
    true_coh = sig / (sig + sigma**2 * x.size)  # white noise: N = sigma^2 N per bin
    return f, h, coh, classic, ref, true_coh


def test_the_smoothed_coherence_is_the_true_one_where_the_classic_scatters():
    f, _, coh, classic, _, true_coh = _resonant_case(repeats=3, seed=4)
    band = (f > 30) & (f < 1400)
    mid = band & (true_coh > 0.3) & (true_coh < 0.97)  # where a threshold at 0.9 decides
    assert mid.sum() > 200
    err_new = np.median(np.abs(coh[mid] - true_coh[mid]))
    err_classic = np.median(np.abs(classic[mid] - true_coh[mid]))
    assert err_new < 0.06 and err_new < 0.7 * err_classic  # (the response's own scatter stays)
    # what a 0.9 threshold keeps: the classic estimate lets through bins truly below 0.8
    assert np.sum((classic >= 0.9) & (true_coh < 0.8) & band) > 5 * max(
        1, np.sum((coh >= 0.9) & (true_coh < 0.8) & band)
    )


def test_the_random_error_bound_holds_where_the_coherence_says():
    from plugins.vibrotactile.roving import random_error_db

    inside, total = 0, 0
    for seed in range(3):
        f, h, coh, _, ref, _ = _resonant_case(repeats=4, seed=seed)
        ok = (f > 30) & (f < 1400) & (coh >= 0.5)
        err = np.abs(20 * np.log10(np.abs(h[ok]) / np.abs(ref[ok])))
        bound = 2 * random_error_db(coh[ok], 4)
        inside += int(np.sum(err <= bound))
        total += int(ok.sum())
    assert total > 1000
    assert 0.9 <= inside / total <= 0.995  # a 2-sigma bound: ~95 % inside, not all
