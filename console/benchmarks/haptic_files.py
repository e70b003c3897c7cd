"""``haptable bench haptic-files``: AHAP and ``.haptic`` import and export time, next to
their error against independent references.

Accuracy:
- ``import_env_err``: a generated ``.haptic`` file of 40 breakpoints (and an AHAP file of
  8 continuous events under an intensity curve) imported, rendered, and its envelope at
  the carrier's crests against the file's breakpoints interpolated by numpy (fraction of
  full scale, away from the 1 ms edges);
- ``round_trip_env_err``: a designed signal exported to each format and imported again,
  Hilbert envelopes compared (fraction of its peak);
- ``breakpoints``: how many the imported envelope kept (the expression must fit one
  library entry).
"""

from __future__ import annotations

import json
import tempfile
import time
from pathlib import Path

import numpy as np
from scipy.signal import find_peaks, hilbert

from console.cli.haptic_commands import scale_for
from console.core.bench_stats import machine_info, summarize_s
from console.signals import ahap, meta_haptic
from console.signals.design import render
from console.signals.expr import parse
from console.signals.haptic_files import export_signal, to_expression

DESIGN = "sine(180 Hz, 60 V, 0.8 s) * adsr(60 ms, 120 ms, 0.5, 200 ms)"


def _haptic_file(n: int) -> tuple[dict, np.ndarray, np.ndarray]:
    rng = np.random.default_rng(3)
    t = np.linspace(0.0, 2.0, n)
    a = np.clip(0.5 + 0.4 * np.sin(2 * np.pi * 1.5 * t) + rng.uniform(-0.05, 0.05, n), 0, 1)
    a[[0, -1]] = 0.0
    amp = [{"time": float(ti), "amplitude": float(ai)} for ti, ai in zip(t, a, strict=True)]
    freq = [{"time": 0.0, "frequency": 0.3}, {"time": 2.0, "frequency": 0.7}]
    doc = {
        "version": {"major": 1, "minor": 0, "patch": 0},
        "signals": {"continuous": {"envelopes": {"amplitude": amp, "frequency": freq}}},
    }
    return doc, t, a


def _ahap_file(n: int) -> tuple[dict, np.ndarray, np.ndarray]:
    events, t_ref, a_ref = [], [0.0], [0.0]
    for i in range(n):
        t0, level = 0.25 * i, 0.3 + 0.6 * i / max(n - 1, 1)
        params = [
            {"ParameterID": "HapticIntensity", "ParameterValue": level},
            {"ParameterID": "HapticSharpness", "ParameterValue": i / max(n - 1, 1)},
            {"ParameterID": "AttackTime", "ParameterValue": 0.04},
            {"ParameterID": "ReleaseTime", "ParameterValue": 0.06},
        ]
        ev = {"Time": t0, "EventType": "HapticContinuous", "EventDuration": 0.2}
        events.append({"Event": {**ev, "EventParameters": params}})
        t_ref += [t0, t0 + 0.04, t0 + 0.14, t0 + 0.2]
        a_ref += [0.0, level, level, 0.0]
    doc = {"Version": 1.0, "Pattern": events}
    return doc, np.array(t_ref[1:]), np.array(a_ref[1:])


def _crest_err(x: np.ndarray, fs: int, t_ref, a_ref, peak_v: float) -> float:
    k, _ = find_peaks(np.abs(x))
    t = k / fs
    knots = np.asarray(t_ref)
    ok = np.min(np.abs(t[:, None] - knots[None, :]), axis=1) > 3e-3
    ref = np.interp(t, t_ref, a_ref) * peak_v
    return float(np.max(np.abs(np.abs(x[k])[ok] - ref[ok])) / peak_v)


def run(ctx, quick: bool) -> dict:
    scale = scale_for(ctx.profile, None)
    fs = scale.fs
    reps = 3 if quick else 15
    out: dict = {"timing": {}, "accuracy": {}, "sample_rate_hz": fs}
    with tempfile.TemporaryDirectory() as d:
        files = {
            "haptic 40 breakpoints": (meta_haptic, "a.haptic", _haptic_file(40)),
            "ahap 8 events": (ahap, "b.ahap", _ahap_file(8)),
        }
        for label, (mod, name, (doc, t_ref, a_ref)) in files.items():
            path = Path(d) / name
            path.write_text(json.dumps(doc), encoding="utf-8")
            times, expr = [], ""
            for _ in range(reps):
                t0 = time.perf_counter()
                expr, _summary = to_expression(mod.read(path), scale)
                times.append(time.perf_counter() - t0)
            x = render(parse(expr), fs)
            out["timing"][f"import {label}"] = summarize_s(times)
            out["accuracy"][f"import_env_err {label}"] = _crest_err(
                x, fs, t_ref, a_ref, scale.peak_v
            )
            out["accuracy"][f"breakpoints {label}"] = expr.count("%")
        x0 = render(parse(DESIGN), fs)
        for fmt, mod in (("ahap", ahap), ("haptic", meta_haptic)):
            times = []
            for _ in range(reps):
                t0 = time.perf_counter()
                text = mod.write(export_signal(x0, scale, "bench"), "bench")
                times.append(time.perf_counter() - t0)
            out["timing"][f"export {fmt}"] = summarize_s(times)
            path = Path(d) / f"rt.{fmt}"
            path.write_text(text, encoding="utf-8")
            x1 = render(parse(to_expression(mod.read(path), scale)[0]), fs)
            n = min(x0.size, x1.size)
            err = np.max(np.abs(np.abs(hilbert(x0[:n])) - np.abs(hilbert(x1[:n])))) / 60.0
            out["accuracy"][f"round_trip_env_err {fmt}"] = float(err)
    out["machine"] = machine_info()
    return out
