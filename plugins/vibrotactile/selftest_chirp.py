"""The self-test's chirp, written out in NumPy: an exponential sweep with raised-cosine
fades, then silence for the ring-down (one record per path).

    x(t) = level sin(2 pi f0 T / ln(f1/f0) ((f1/f0)^(t/T) - 1)),  0 <= t < T

is scipy.signal.chirp's 'logarithmic' sweep at phi = -90 (the roving map's ``chirp_v``;
a test holds the two to each other). Importing scipy.signal costs ~1.4 s of CPU (20 s of
wall time on a loaded machine) that a technician waits for at every ``haptable
selftest``; this module needs only NumPy.
"""

from __future__ import annotations

import math

import numpy as np

from console.plugin_api import EXCITATIONS, OutputPlan, Segment


def sweep_v(
    level_v: float, f0_hz: float, f1_hz: float, sweep_s: float, fade_s: float, fs_hz: int
) -> np.ndarray:
    """The exponential chirp (volts at the patches), faded in and out over ``fade_s``."""
    n = int(round(sweep_s * fs_hz))
    t = np.arange(n) / fs_hz
    beta = f1_hz / f0_hz
    x = level_v * np.sin(
        2 * math.pi * f0_hz * sweep_s / math.log(beta) * (beta ** (t / sweep_s) - 1)
    )
    m = max(1, int(round(fade_s * fs_hz)))
    w = 0.5 * (1 - np.cos(math.pi * np.arange(m) / m))
    x[:m] *= w
    x[n - m :] *= w[::-1]
    return x


def record_v(s, fs_hz: int) -> np.ndarray:
    """One record of ``s`` (``RovingSettings``-like): the chirp, then ``tail_s`` of silence."""
    x = sweep_v(s.level_v, s.f_start_hz, s.f_stop_hz, s.sweep_s, s.fade_s, fs_hz)
    return np.concatenate([x, np.zeros(int(round(s.tail_s * fs_hz)))])


def path_plan(exc: str, s, fs_hz: int) -> tuple[OutputPlan, np.ndarray]:
    """The plan of one path (``repeats`` records; PALL: every patch) and one record."""
    record = record_v(s, fs_hz)
    x = np.tile(record, s.repeats)
    patches = frozenset(EXCITATIONS[:4]) if exc == "PALL" else frozenset({exc})
    seg = Segment(x, np.zeros_like(x), patches, False, f"self-test {exc}")
    return OutputPlan(fs_hz, (seg,), f"self-test {exc}", 0.0), record
