"""``haptable bench plate``: accuracy next to speed for the plate twin."""

from __future__ import annotations

import time
from dataclasses import replace

import numpy as np

from console.plugin_api import machine_info, summarize_s

from . import model, ritz
from .frf import missed_peaks
from .model import build_twin, default_params, grid_points_mm, params_from_profile, truncation_error
from .reference import LAMBDA_TABLE
from .vibrometer import SweepSettings, measure

_CPU: list[float] = []


def _timed(fn, repeat: int) -> tuple[object, list[float]]:
    """Wall times of ``repeat`` calls; the process CPU times go to ``_CPU`` (see _cpu)."""
    out, times = None, []
    _CPU.clear()
    for _ in range(repeat):
        t, c = time.perf_counter(), time.process_time()
        out = fn()
        times.append(time.perf_counter() - t)
        _CPU.append(time.process_time() - c)
    return out, times


def _summ(times: list[float]) -> dict:
    """Wall p50/p99 plus the median CPU time (robust when other jobs load the machine)."""
    out = summarize_s(times)
    out["cpu_p50_ms"] = float(np.median(_CPU) * 1e3) if _CPU else float("nan")
    return out


def modal_solve_table(orders: tuple[int, ...], repeat: int) -> list[dict]:
    """Solve time and worst lambda error vs FACTS per basis order and edge case."""
    rows = []
    for n in orders:
        for (edges, aspect, nu), ref in LAMBDA_TABLE.items():
            plate = ritz.nondim_plate(aspect, nu)

            def solve(plate=plate, edges=edges, n=n):
                ritz.cache_clear()
                return ritz.solve_modes(plate, edges, n)

            modes, times = _timed(solve, repeat)
            lam = modes.lam[modes.n_rigid : modes.n_rigid + 6]
            rows.append(
                {
                    "basis_order": n,
                    "edges": edges,
                    "aspect": round(aspect, 5),
                    "max_rel_error": float(np.max(np.abs(lam / np.array(ref) - 1))),
                    "solve_ms_p50": summarize_s(times)["p50_ms"],
                    "solve_cpu_ms_p50": float(np.median(_CPU) * 1e3),
                }
            )
    return rows


def run_bench(profile=None, quick: bool = False) -> dict:
    repeat = 2 if quick else 5
    params = params_from_profile(profile) if profile is not None else default_params()
    import os

    out: dict = {"machine": machine_info(), "load_average_1min": os.getloadavg()[0]}
    orders = (12, 16, 20) if quick else (10, 12, 14, 16, 18, 20, 22, 24)
    out["modal_solve"] = modal_solve_table(orders, repeat)

    # sim plate: first 10 frequencies and the FRF vs basis order (reference: order 28)
    x, y = grid_points_mm(profile)
    f_chk = np.arange(5.0, params.band_max_hz, 0.5)
    ref_twin = build_twin(replace(params, basis_order=28))
    ref = ref_twin.freq_hz[:10]
    h_ref = ref_twin.frf_um_per_v(x, y, f_chk)
    conv = []
    for n in orders:
        ritz.cache_clear()
        model.cache_clear()
        t = time.perf_counter()
        tw = build_twin(replace(params, basis_order=n))
        dt = time.perf_counter() - t
        h = tw.frf_um_per_v(x, y, f_chk)
        conv.append(
            {
                "basis_order": n,
                "max_rel_freq_error_vs_n28": float(np.max(np.abs(tw.freq_hz[:10] / ref - 1))),
                "frf_max_rel_error_vs_n28": float(np.abs(h - h_ref).max() / np.abs(h_ref).max()),
                "build_ms": dt * 1e3,
            }
        )
    out["sim_convergence"] = conv
    twin = build_twin(params)
    out["sim_first_freqs_hz"] = [round(float(f), 2) for f in twin.freq_hz[:12]]
    out["sim_modes_kept"] = int(twin.freq_hz.size)

    # FRF: truncation error vs modes kept vs time (84 points x 2501 bins x 5 excitations)

    trunc = truncation_error(params)
    f = np.linspace(0.0, params.band_max_hz, 2501)
    for row in trunc:
        tw = build_twin(
            replace(params, mode_margin=row["mode_margin"], static_residual=row["static_residual"])
        )
        _, times = _timed(lambda tw=tw: tw.frf_um_per_v(x, y, f), repeat)
        row["frf_84pts_2501bins_ms_p50"] = summarize_s(times)["p50_ms"]
        row["frf_84pts_2501bins_cpu_ms_p50"] = float(np.median(_CPU) * 1e3)
    out["frf_truncation"] = trunc
    h = twin.frf_um_per_v(x, y, f[f >= 5.0])
    out["sim_peak_frf_um_per_v"] = {
        e: float(np.abs(h[i]).max()) for i, e in enumerate(("PA", "PB", "PC", "PD", "PALL"))
    }

    # many points (the flow / interpolation code's use)
    xs = np.random.default_rng(0).uniform(0, params.plate.a_m * 1e3, 10000)
    ys = np.random.default_rng(1).uniform(0, params.plate.b_m * 1e3, 10000)
    _, times = _timed(lambda: twin.frf_um_per_v(xs, ys, np.array([465.0])), repeat)
    out["frf_10k_points_1_bin_ms"] = _summ(times)

    # vibrometer: 84 points x 5 excitations x 3 sweeps
    s = SweepSettings(record_s=4.0, sweep_s=3.0) if quick else SweepSettings()
    res, times = _timed(lambda: measure(twin, x, y, s), 1 if quick else 2)
    v = res["valid"]
    exact = twin.frf_um_per_v(x, y, res["freqs_hz"][v])
    err = np.abs(res["frf"][..., v] - exact)
    out["vibrometer"] = {
        "points": int(x.size),
        "excitations": 5,
        "record_s": s.record_s,
        "df_hz": 1.0 / s.record_s,
        "sweeps": s.sweeps,
        "max_abs_error_um_per_v": float(err.max()),
        "max_error_rel_to_peak": float(err.max() / np.abs(exact).max()),
        "ringdown_left": res["meta"]["ringdown_left"],
        "peaks_missed_by_grid_at_damping": missed_peaks(
            res["freqs_hz"], twin.freq_hz, params.damping_ratio
        ),
        "peaks_missed_by_grid_at_0.1pct_damping": len(
            missed_peaks(res["freqs_hz"], twin.freq_hz, 0.001)
        ),
        "time": _summ(times),
    }
    return out
