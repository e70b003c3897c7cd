"""Waveform building blocks in volts: ramps, tones, sweeps. Pure numpy."""

from __future__ import annotations

import numpy as np


def ramp_envelope(n: int, ramp_n: int) -> np.ndarray:
    """Linear rise over ``ramp_n`` samples, flat, linear fall; exactly 0 at both ends."""
    env = np.ones(n)
    r = max(1, min(ramp_n, n // 2))
    rise = np.arange(r) / r
    env[:r] = rise
    env[n - r :] = np.minimum(env[n - r :], rise[::-1])
    env[-1] = 0.0
    return env


def tone(
    freq_hz: float, amp_v: float, dur_s: float, fs: int, ramp_s: float = 0.02, phase: float = 0.0
) -> np.ndarray:
    """A sine of peak ``amp_v`` under a linear ramp envelope."""
    n = max(2, round(dur_s * fs))
    t = np.arange(n) / fs
    return amp_v * np.sin(2 * np.pi * freq_hz * t + phase) * ramp_envelope(n, round(ramp_s * fs))


def linear_chirp(
    f0_hz: float, f1_hz: float, amp_v: float, dur_s: float, fs: int, ramp_s: float = 0.02
) -> np.ndarray:
    """A linear sine sweep from ``f0_hz`` to ``f1_hz`` under a ramp envelope."""
    n = max(2, round(dur_s * fs))
    t = np.arange(n) / fs
    phase = 2 * np.pi * (f0_hz * t + 0.5 * (f1_hz - f0_hz) / dur_s * t**2)
    return amp_v * np.sin(phase) * ramp_envelope(n, round(ramp_s * fs))
