"""Signal designer benchmark: parse, render and check time per expression (what the
console waits for between Enter and the plots, and before an audition), next to the
renderers' error against analytic references.

Accuracy (independent references):
- ``sine_freq_err_hz``: the dominant frequency of a 1 s sine at 7 frequencies (the
  interpolated spectral peak) against the frequency asked for;
- ``chirp_inst_freq_rel_err``: a linear and a log chirp's instantaneous frequency (the
  phase of the analytic signal, scipy's Hilbert transform) against ``f(t)`` in closed form;
- ``sine_vs_tone_max_abs_v``: the designed ``sine * ramp`` against ``console.signals.waveforms.tone``;
- ``adsr_level_err``: ADSR envelope levels at the segment ends against their set values.
"""

from __future__ import annotations

import time

import numpy as np
from scipy.signal import hilbert

from console.core.bench_stats import machine_info, summarize_s
from console.safety import Limits, check_plan
from console.signals.design import dominant_hz, parse_target, render, signal_plan
from console.signals.expr import parse
from console.signals.waveforms import tone

CASES = {
    "tone 1 s": "sine(250 Hz, 20 V, 1 s) * ramp(20 ms)",
    "pulses 2.1 s": "seq(sine(250 Hz, 40 V, 0.5 s) * adsr(10 ms, 50 ms, 0.7, 100 ms), "
    "silence(0.2 s)) * 3",
    "sweep 3 s": "chirp(10 Hz, 625 Hz, 10 V, 3 s) * ramp(20 ms)",
    "am noise 10 s": "(noise(2 V, 10 s, seed=1) + sine(180 Hz, 20 V, 10 s)) "
    "* sine(4 Hz, 100 %, 10 s) * ramp(10 ms)",
    "60 s tone": "sine(200 Hz, 20 V, 60 s) * ramp(10 ms)",
}


def _accuracy(fs: int) -> dict[str, float]:
    freq_err = 0.0
    for f in (31.0, 100.0, 175.5, 250.0, 333.3, 625.0, 1000.0):
        y = render(parse(f"sine({f} Hz, 1 V, 1 s)"), fs)
        freq_err = max(freq_err, abs(dominant_hz(y, fs) - f))
    t = np.arange(2 * fs) / fs
    chirp_err = 0.0
    for expr, ref in (
        ("chirp(100 Hz, 500 Hz, 1 V, 2 s)", 100 + 200 * t),
        ("logchirp(100 Hz, 1 kHz, 1 V, 2 s)", 100 * 10 ** (t / 2)),
    ):
        phase = np.unwrap(np.angle(hilbert(render(parse(expr), fs))))
        inst = np.diff(phase) * fs / (2 * np.pi)
        mid = slice(fs // 10, -fs // 10)
        chirp_err = max(chirp_err, float(np.max(np.abs(inst[mid] / ref[:-1][mid] - 1))))
    designed = render(parse("sine(250 Hz, 20 V, 1 s) * ramp(20 ms)"), fs)
    x = render(parse("adsr(100 ms, 100 ms, 50 %, 200 ms) * square(0.5 Hz, 1 V, 1 s)"), fs)
    levels = [(x[round(0.1 * fs)], 1.0), (x[round(0.2 * fs)], 0.5), (x[round(0.8 * fs)], 0.5)]
    return {
        "sine_freq_err_hz": freq_err,
        "chirp_inst_freq_rel_err": chirp_err,
        "sine_vs_tone_max_abs_v": float(np.max(np.abs(designed - tone(250.0, 20.0, 1.0, fs)))),
        "adsr_level_err": float(max(abs(a - b) for a, b in levels)),
    }


def run(ctx, quick: bool) -> dict:
    profile = ctx.profile
    limits = Limits.from_profile(profile)
    fs = limits.sample_rate_hz
    reps = 5 if quick else 30
    target = parse_target("PA")
    timing: dict[str, dict] = {}
    for label, expr in CASES.items():
        parse_s, render_s, check_s = [], [], []
        for _ in range(reps):
            t0 = time.perf_counter()
            node = parse(expr)
            t1 = time.perf_counter()
            x = render(node, fs, max_s=float(profile.get("limits.max_plan_s")))
            t2 = time.perf_counter()
            check_plan(signal_plan(x, target, fs, label), limits)
            t3 = time.perf_counter()
            parse_s.append(t1 - t0)
            render_s.append(t2 - t1)
            check_s.append(t3 - t2)
        timing[label] = {
            "parse": summarize_s(parse_s),
            "render": summarize_s(render_s),
            "gate_check": summarize_s(check_s),
        }
    return {
        "sample_rate_hz": fs,
        "timing": timing,
        "accuracy": _accuracy(fs),
        "machine": machine_info(),
    }
