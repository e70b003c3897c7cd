"""Waveform building blocks in volts: ramps, tones, sweeps. Pure numpy.

Every length is checked before its array is built (``plan_samples``): a NaN, negative
or huge duration is refused with one line instead of allocating.
"""

from __future__ import annotations

import math

import numpy as np

from console.core.errors import UserError
from console.core.plain_numbers import plain_s

#: The longest plan any profile may allow (``[limits] max_plan_s`` is at most this).
MAX_PLAN_S = 3600.0


def check_duration(total_s: float, max_s: float, what: str) -> float:
    """``total_s`` if it is a finite, non-negative number of seconds within ``max_s``
    (the profile's ``[limits] max_plan_s``); else a one-line ``UserError``."""
    if isinstance(total_s, bool) or not isinstance(total_s, (int, float)):
        raise UserError(f"{what}: duration {total_s!r} is not a number of seconds")
    if not math.isfinite(total_s) or total_s < 0:
        raise UserError(f"{what}: duration {total_s!r} s; give a finite, positive length")
    if total_s > max_s:
        raise UserError(
            f"{what}: {plain_s(total_s, 4)} is longer than [limits] max_plan_s = {plain_s(max_s)}; "
            "shorten it (or raise max_plan_s in the profile)"
        )
    return float(total_s)


def plan_samples(dur_s: float, fs: int, *, max_s: float = MAX_PLAN_S, what: str = "signal") -> int:
    """Samples for ``dur_s`` at ``fs`` (at least 2), checked before anything is allocated."""
    return max(2, round(check_duration(dur_s, max_s, what) * fs))


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
    freq_hz: float,
    amp_v: float,
    dur_s: float,
    fs: int,
    ramp_s: float = 0.02,
    phase: float = 0.0,
    *,
    max_s: float = MAX_PLAN_S,
) -> np.ndarray:
    """A sine of peak ``amp_v`` under a linear ramp envelope (``dur_s`` <= ``max_s``)."""
    n = plan_samples(dur_s, fs, max_s=max_s, what=f"{freq_hz:g} Hz tone")
    t = np.arange(n) / fs
    return amp_v * np.sin(2 * np.pi * freq_hz * t + phase) * ramp_envelope(n, round(ramp_s * fs))


def linear_chirp(
    f0_hz: float,
    f1_hz: float,
    amp_v: float,
    dur_s: float,
    fs: int,
    ramp_s: float = 0.02,
    *,
    max_s: float = MAX_PLAN_S,
) -> np.ndarray:
    """A linear sine sweep from ``f0_hz`` to ``f1_hz`` under a ramp envelope."""
    n = plan_samples(dur_s, fs, max_s=max_s, what=f"{f0_hz:g}-{f1_hz:g} Hz sweep")
    t = np.arange(n) / fs
    phase = 2 * np.pi * (f0_hz * t + 0.5 * (f1_hz - f0_hz) / dur_s * t**2)
    return amp_v * np.sin(phase) * ramp_envelope(n, round(ramp_s * fs))
