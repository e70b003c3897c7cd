"""``haptable bench vibration``: accuracy next to speed for the vibrotactile pipeline.

Reference: the analytic simply supported plate (exact FRF anywhere), its map on the
7 x 12 grid at 0.5 Hz bins to 625 Hz.
"""

from __future__ import annotations

import contextlib
import os
import time
from concurrent.futures import ProcessPoolExecutor
from pathlib import Path

import numpy as np

from console.plugin_api import machine_info, make_map, summarize_s
from plugins.vibrotactile.analytic_plate import SSPlate, analytic_map, default_freq_hz
from plugins.vibrotactile.thresholds import Perception

BANDS = ((5, 150), (150, 300), (300, 450), (450, 625))
METHODS = ("bilinear", "keys", "spline", "spline5", "modal")


def _timed(fn, reps: int) -> tuple[list[float], list[float]]:
    """(wall, CPU) durations: on a loaded machine the CPU time of a single-threaded call
    is the better estimate of its unloaded wall time."""
    wall, cpu = [], []
    for _ in range(reps):
        t0, c0 = time.perf_counter(), time.process_time()
        fn()
        wall.append(time.perf_counter() - t0)
        cpu.append(time.process_time() - c0)
    return wall, cpu


def _summ(fn, reps: int) -> dict:
    wall, cpu = _timed(fn, reps)
    out = summarize_s(wall)
    out["cpu_p50_ms"] = summarize_s(cpu)["p50_ms"]
    return out


def bench_interpolation(plate, m, n_points: int, reps: int) -> dict:
    # lazy: SciPy loads only when this runs
    from plugins.vibrotactile.interp import interpolate

    rng = np.random.default_rng(0)
    lo, hi = m.points_mm.min(axis=0), m.points_mm.max(axis=0)
    xy = rng.uniform(lo, hi, size=(n_points, 2))
    ref = plate.frf_um_per_v(xy, m.freq_hz)
    f = m.freq_hz
    res = {}
    for meth in METHODS:
        t0 = time.perf_counter()
        h = interpolate(m, xy, meth)  # modal: includes its fit (once per map)
        first_s = time.perf_counter() - t0
        errs = {}
        for b0, b1 in BANDS:
            s = (f >= b0) & (f < b1)
            per_pt = np.linalg.norm(h[..., s] - ref[..., s], axis=(0, 2)) / np.linalg.norm(
                ref[..., s], axis=(0, 2)
            )
            errs[f"{b0}-{b1}_hz"] = {
                "rel_l2": float(
                    np.linalg.norm(h[..., s] - ref[..., s]) / np.linalg.norm(ref[..., s])
                ),
                "p95_point": float(np.percentile(per_pt, 95)),
            }
        one = xy[:1]
        t = _summ(lambda one=one, meth=meth: interpolate(m, one, meth), reps)
        res[meth] = {"error": errs, "query_all_bins_one_point": t, "first_call_s": first_s}
    return res


TWIN_METHODS = ("bilinear", "keys", "spline", "modal")
TWIN_BANDS = ((5, 150), (150, 300), (300, 625), (5, 625))
NOISE_REL, NOISE_FLOOR = 0.02, 1e-3  # see add_ldv_noise


def add_ldv_noise(m, rel: float = NOISE_REL, floor: float = NOISE_FLOOR, seed: int = 1):
    """The map with complex Gaussian noise of ``rel`` x |H| per bin plus ``floor`` x the
    map's RMS per excitation: an LDV's H1 over 3 averages at coherence 0.999 has a random
    error of ~1.3 %; speckle and drop-outs on glass add to it, hence 2 %."""
    rng = np.random.default_rng(seed)
    h = m.frf_um_per_v
    std = rel * np.abs(h) + floor * np.sqrt(np.mean(np.abs(h) ** 2, axis=(1, 2), keepdims=True))
    n = (rng.standard_normal(h.shape) + 1j * rng.standard_normal(h.shape)) * std / np.sqrt(2)
    return make_map(h + n, m.freq_hz, m.points, m.points_mm, m.excitations, m.masked)


def _lattice_profile(profile, factor: int, noise: float | None):
    """The profile with a grid ``factor`` times denser (same origin and extent) and,
    if given, the vibrometer's noise density replaced."""
    import copy
    import dataclasses

    data = copy.deepcopy(profile.data)
    g = data.setdefault("grid", {})
    g["rows"] = (int(profile.get("grid.rows", 7)) - 1) * factor + 1
    g["columns"] = (int(profile.get("grid.columns", 12)) - 1) * factor + 1
    g["pitch_mm"] = float(profile.get("grid.pitch_mm", 60.0)) / factor
    if noise is not None:
        data.setdefault("vibrometer", {})["noise_um_per_s_per_sqrt_hz"] = noise
    return dataclasses.replace(profile, data=data)


def twin_maps(ctx):
    """(grid map, off-grid points (N, 2), their exact FRFs (E, N, F), twin-LDV noisy map):
    the profile's twin vibrometer (through its registration) on a lattice twice as dense
    as the grid, noise-free: its even rows and columns are the map, the rest (midpoints
    in x, in y and cell centres) the reference."""
    dev = ctx.pm.get("vibrometer", "twin")
    r = dev.factory(_lattice_profile(ctx.profile, 2, 0.0)).measure()
    rows = int(ctx.profile.get("grid.rows", 7))
    cols = int(ctx.profile.get("grid.columns", 12))
    idx = np.arange((rows - 1) * 2 + 1)[:, None] * ((cols - 1) * 2 + 1) + np.arange(
        (cols - 1) * 2 + 1
    )
    on = np.zeros(idx.shape, bool)
    on[::2, ::2] = True
    grid_i, off_i = idx[on], idx[~on]

    def sub(frf, where):
        return make_map(
            frf[:, where],
            r["freq_hz"],
            np.arange(1, where.size + 1),
            r["points_mm"][where],
            r["excitations"],
            r["masked"],
            source="twin lattice subset",
        )

    m = sub(r["frf_um_per_v"], grid_i)
    ldv = dev.factory(ctx.profile).measure()  # the twin LDV's own noise on the real grid
    m_ldv = make_map(**{k: v for k, v in ldv.items() if k != "meta"})
    return m, r["points_mm"][off_i], r["frf_um_per_v"][:, off_i], m_ldv


def bench_twin_interpolation(ctx, quick: bool) -> dict:
    """Error vs time of the four methods on the twin, clean and with LDV noise."""
    # lazy: SciPy loads only when this runs
    from plugins.vibrotactile import modal_fit
    from plugins.vibrotactile.interp import interpolate

    m, xy, ref, m_ldv = twin_maps(ctx)
    f = m.freq_hz
    ref_rms = np.sqrt(np.mean(np.abs(m.frf_um_per_v) ** 2))
    maps = {
        "clean": m,
        f"noise_{NOISE_REL * 100:g}pct_rel": add_ldv_noise(m),
    }
    if not quick:
        maps["twin_ldv_noise"] = m_ldv
    out = {
        "reference": "plate twin, noise-free simulated LDV on a 30 mm lattice: the 60 mm grid "
        f"is the map, the other {xy.shape[0]} points (midpoints, cell centres) the reference",
        "noise": f"{NOISE_REL * 100:g} % of |H| per bin + {NOISE_FLOOR * 100:g} % of the map RMS "
        "(complex Gaussian); twin_ldv_noise: the twin vibrometer's own velocity noise",
        "rms_um_per_v": float(ref_rms),
    }
    for name, mp in maps.items():
        rows = {}
        for meth in TWIN_METHODS:
            fit_s = fit_cpu = None
            if meth == "modal":
                t0, c0 = time.perf_counter(), time.process_time()
                modal_fit.modal_model(mp)
                fit_s, fit_cpu = time.perf_counter() - t0, time.process_time() - c0
            h = interpolate(mp, xy, meth)
            errs = {}
            for b0, b1 in TWIN_BANDS:
                s = (f >= b0) & (f < b1) & ~mp.masked
                errs[f"{b0}-{b1}_hz"] = float(
                    np.linalg.norm(h[..., s] - ref[..., s]) / np.linalg.norm(ref[..., s])
                )
            one = xy[:1]
            q = _summ(
                lambda one=one, meth=meth, mp=mp: interpolate(mp, one, meth), 5 if quick else 30
            )
            rows[meth] = {
                "rel_l2": errs,
                "fit_s": fit_s,
                "fit_cpu_s": fit_cpu,
                "query_all_bins_one_point": q,
            }
            if meth == "modal":
                mdl = modal_fit.modal_model(mp)
                rows[meth]["poles"] = int(mdl.poles.size)
                rows[meth]["grid_fit_rel_l2"] = mdl.grid_fit_error
        out[name] = rows
    return out


def bench_tables(m, reps: int) -> dict:
    # lazy: SciPy loads only when this runs
    from plugins.vibrotactile.tables import build_tables, query_indices, query_points

    build = _summ(lambda: build_tables(m), reps)
    t = build_tables(m)
    rng = np.random.default_rng(1)
    pairs = rng.integers(0, m.points.size, size=(20000, 2))
    t0, c0 = time.perf_counter(), time.process_time()
    for a, p in pairs:
        query_indices(t, int(a), int(p))
    per_query = (time.perf_counter() - t0) / len(pairs)
    per_query_cpu = (time.process_time() - c0) / len(pairs)
    arb = _summ(lambda: query_points(t, (250.0, 200.0), (330.0, 230.0)), max(5, reps * 4))
    return {
        "build_84x84x5": build,
        "query_grid_pair_cpu_us": per_query_cpu * 1e6,
        "bins": int(((m.freq_hz <= 650) & ~m.masked).sum()),
        "query_grid_pair_us": per_query * 1e6,
        "query_arbitrary_points": arb,
    }, t


def _table_chunk(args):
    m, per, centers, kw = args
    # lazy: SciPy loads only when this runs
    from plugins.vibrotactile.hand import hand_flow_table

    try:  # one BLAS thread per process: the processes are the parallelism
        from threadpoolctl import threadpool_limits

        limit = threadpool_limits(1)
    except ImportError:  # threadpoolctl comes with scikit-learn; without it run as is
        limit = contextlib.nullcontext()
    t0 = time.process_time()
    with limit:
        out = hand_flow_table(m, per, centers=centers, **kw)
    out["cpu_s"] = np.array([time.process_time() - t0])
    return out


def hand_flow_table_parallel(m, per, centers, workers: int = 2, **kw) -> dict:
    """``hand_flow_table`` split over ``workers`` processes (by rows of centres)."""
    if workers <= 1:
        return _table_chunk((m, per, centers, kw))
    chunks = np.array_split(centers, workers)
    with ProcessPoolExecutor(workers) as ex:
        parts = list(ex.map(_table_chunk, [(m, per, c, kw) for c in chunks]))
    return {k: np.concatenate([p[k] for p in parts]) for k in parts[0]}


def bench_hand(m, per, quick: bool) -> dict:
    # lazy: SciPy loads only when this runs
    from plugins.vibrotactile.hand import DIRECTIONS, hand_flow, region_centers

    centers = region_centers(m, 120.0, 10.0)
    rng = np.random.default_rng(2)
    sample = centers[rng.choice(len(centers), 4 if quick else 12, replace=False)]
    exact_t, screen_t, exact_c, screen_c, same, loss = [], [], [], [], 0, []
    for c in sample:
        for d in DIRECTIONS[:2] if quick else DIRECTIONS:
            t0, c0 = time.perf_counter(), time.process_time()
            ex = hand_flow(m, c, d, per)
            t1, c1 = time.perf_counter(), time.process_time()
            sc = hand_flow(m, c, d, per, screen_stride=3)
            t2, c2 = time.perf_counter(), time.process_time()
            exact_t.append(t1 - t0)
            screen_t.append(t2 - t1)
            exact_c.append(c1 - c0)
            screen_c.append(c2 - c1)
            if ex["ok"] and sc["ok"]:
                pairs = list(zip(ex["parts"], sc["parts"], strict=True))
                same += all(
                    (a["actuator"], a["frequency_hz"]) == (b["actuator"], b["frequency_hz"])
                    for a, b in pairs
                )
                loss.extend(a["margin_db"] - b["margin_db"] for a, b in pairs)
    n_cmp = len(exact_t)
    todo = centers if not quick else centers[:: max(1, len(centers) // 60)]
    workers = min(2, os.cpu_count() or 1)
    t0 = time.perf_counter()
    table = hand_flow_table_parallel(m, per, todo, workers=workers)
    whole = time.perf_counter() - t0
    est = whole * len(centers) / len(todo)
    cpu = float(table["cpu_s"].sum()) * len(centers) / len(todo)
    return {
        "region_exact_one_direction": {
            **summarize_s(exact_t),
            "cpu_p50_ms": summarize_s(exact_c)["p50_ms"],
        },
        "region_screened_one_direction": {
            **summarize_s(screen_t),
            "cpu_p50_ms": summarize_s(screen_c)["p50_ms"],
        },
        "screened_same_choice_fraction": same / max(1, n_cmp),
        "screened_within_0p5_db_fraction": float(np.mean(np.array(loss) <= 0.5)) if loss else 1.0,
        "screened_margin_loss_db_median": float(np.median(loss)) if loss else 0.0,
        "screened_margin_loss_db_max": float(np.max(loss)) if loss else 0.0,
        "whole_table_regions": int(len(centers)),
        "whole_table_regions_timed": int(len(todo)),
        "whole_table_s": float(est),
        "whole_table_measured_s": float(whole),
        "whole_table_cpu_s": cpu,
        "load_average_1min": os.getloadavg()[0],
        "whole_table_workers": workers,
        "whole_table_ok_fraction_by_direction": dict(
            zip(DIRECTIONS, table["ok"].mean(axis=0).round(3).tolist(), strict=True)
        ),
    }, table


def run_bench(ctx, quick: bool, report_dir: str | None = None) -> dict:
    plate = SSPlate()
    m = analytic_map(plate, default_freq_hz(625.0, 0.1))  # the twin vibrometer's 0.1 Hz lines
    per = Perception()
    if ctx is not None and hasattr(ctx, "profile"):
        per = Perception.from_section(ctx.profile.section("perception"))
    interp = bench_interpolation(plate, m, 60 if quick else 300, 50 if quick else 300)
    twin_interp = None
    if ctx is not None and hasattr(ctx, "pm") and hasattr(ctx, "profile"):
        twin_interp = bench_twin_interpolation(ctx, quick)
    tables, t = bench_tables(m, 3 if quick else 10)
    hand, htable = bench_hand(m, per, quick)
    out = {
        "reference": "analytic SSSS glass plate 743.46 x 447.29 x 3.18 mm, zeta 1 %, 7 x 12 grid, 0.1 Hz bins to 625 Hz",
        "interpolation": interp,
        "interpolation_twin": twin_interp,
        "tables": tables,
        "flow_under_hand": hand,
        "targets": {"table_build_ms": 1000, "query_us": 50, "whole_table_flow_s": 60},
        "machine": machine_info(),
        "quick": quick,
        "load_average_1min": os.getloadavg()[0],
    }
    if report_dir:
        out["report"] = str(write_report(Path(report_dir), out, t, htable))
    return out


def write_report(d: Path, res: dict, tables, htable) -> Path:
    """Markdown + PNG plots."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    d.mkdir(parents=True, exist_ok=True)
    interp = res["interpolation"]
    fig, ax = plt.subplots(1, 2, figsize=(10, 4))
    centers = [(a + b) / 2 for a, b in BANDS]
    for meth, r in interp.items():
        errs = [r["error"][f"{a}-{b}_hz"]["rel_l2"] * 100 for a, b in BANDS]
        ax[0].plot(centers, errs, "o-", label=meth)
        ax[1].scatter([r["query_all_bins_one_point"]["cpu_p50_ms"] * 1e3], [max(errs)], label=meth)
    ax[0].set(
        xlabel="band centre (Hz)",
        ylabel="relative L2 error (%)",
        title="FRF interpolation error vs exact",
    )
    ax[1].set(
        xlabel="CPU time per point query, all bins (us)",
        ylabel="worst-band error (%)",
        title="error vs time",
    )
    for a in ax:
        a.legend()
        a.grid(alpha=0.3)
    fig.tight_layout()
    fig.savefig(d / "interpolation.png", dpi=100)
    plt.close(fig)

    fig, ax = plt.subplots(1, 3, figsize=(14, 4))
    im = ax[0].imshow(tables.max_diff_um_per_v, cmap="viridis")
    fig.colorbar(im, ax=ax[0])
    ax[0].set(title="(a) max difference um/V", xlabel="passive", ylabel="active")
    im = ax[1].imshow(tables.freq_hz, cmap="plasma")
    fig.colorbar(im, ax=ax[1])
    ax[1].set(title="(b) frequency Hz", xlabel="passive")
    im = ax[2].imshow(
        np.where(tables.actuator < 0, np.nan, tables.actuator), cmap="tab10", vmin=0, vmax=9
    )
    ax[2].set(title="(c) actuator 0..4 = " + " ".join(tables.excitations), xlabel="passive")
    fig.tight_layout()
    fig.savefig(d / "tables.png", dpi=100)
    plt.close(fig)

    h = res["flow_under_hand"]
    fig, ax = plt.subplots(figsize=(6, 3.5))
    c = htable["centers_mm"]
    ok = htable["ok"].sum(axis=1)
    sc = ax.scatter(c[:, 0], c[:, 1], c=ok, cmap="RdYlGn", vmin=0, vmax=4, s=12)
    fig.colorbar(sc, ax=ax, label="directions with a valid flow")
    ax.set(
        xlabel="hand centre x (mm)",
        ylabel="y (mm)",
        title="flow under a hand (1 cm steps)",
        aspect="equal",
    )
    fig.tight_layout()
    fig.savefig(d / "hand_flow.png", dpi=100)
    plt.close(fig)

    tb = res["tables"]
    lines = [
        "# Vibrotactile benchmark",
        "",
        f"Reference: {res['reference']}. Machine: {res['machine']['cpu']}, {res['machine']['cores']} cores."
        + (" (quick run)" if res["quick"] else ""),
        "",
        "## FRF interpolation vs the exact plate (off-grid points)",
        "",
        "Relative L2 error over random off-grid points per band. Times: one point, all excitations and bins,"
        " wall-clock and CPU (the CPU time of a single-threaded call estimates its wall time on an idle"
        " machine).",
        "",
        "| method | " + " | ".join(f"{a}-{b} Hz" for a, b in BANDS) + " | query p50 (us) |",
        "|---|" + "---|" * (len(BANDS) + 1),
    ]
    for meth, r in interp.items():
        errs = " | ".join(f"{r['error'][f'{a}-{b}_hz']['rel_l2'] * 100:.1f} %" for a, b in BANDS)
        q = r["query_all_bins_one_point"]
        lines.append(
            f"| {meth} | {errs} | {q['p50_ms'] * 1e3:.0f} wall / {q['cpu_p50_ms'] * 1e3:.0f} CPU |"
        )
    tw = res.get("interpolation_twin")
    if tw:
        lines += [
            "",
            "## FRF interpolation on the plate twin, clean and noisy",
            "",
            f"{tw['reference']}. Noise: {tw['noise']}. Relative L2 error; modal fit time once"
            " per map, query: one point, all excitations and bins.",
            "",
            "| map | method | "
            + " | ".join(f"{a}-{b} Hz" for a, b in TWIN_BANDS)
            + " | fit (s) | query p50 (ms) |",
            "|---|---|" + "---|" * (len(TWIN_BANDS) + 2),
        ]
        for name, rows in tw.items():
            if not isinstance(rows, dict):
                continue
            for meth, r in rows.items():
                errs = " | ".join(
                    f"{r['rel_l2'][f'{a}-{b}_hz'] * 100:.2f} %" for a, b in TWIN_BANDS
                )
                fit = "-" if r["fit_s"] is None else f"{r['fit_s']:.1f}"
                q = r["query_all_bins_one_point"]["p50_ms"]
                lines.append(f"| {name} | {meth} | {errs} | {fit} | {q:.2f} |")
    lines += [
        "",
        "![interpolation](interpolation.png)",
        "",
        "## Lookup tables (paper Fig. 8)",
        "",
        f"- build, 84 x 84 pairs x 5 excitations x {tb['bins']} bins: p50 {tb['build_84x84x5']['p50_ms']:.0f} ms"
        f" wall, {tb['build_84x84x5']['cpu_p50_ms']:.0f} ms CPU (target < 1000 ms)",
        f"- query, grid pair: {tb['query_grid_pair_us']:.2f} us wall, {tb['query_grid_pair_cpu_us']:.2f} us CPU"
        " (target < 50 us)",
        f"- query, arbitrary points (spline interpolation + search): p50 {tb['query_arbitrary_points']['p50_ms']:.2f}"
        f" ms wall, {tb['query_arbitrary_points']['cpu_p50_ms']:.2f} ms CPU",
        "",
        "![tables](tables.png)",
        "",
        "## Flow under a hand",
        "",
        f"- one region, one direction, exhaustive: p50 {h['region_exact_one_direction']['p50_ms']:.0f} ms wall,"
        f" {h['region_exact_one_direction']['cpu_p50_ms']:.0f} ms CPU",
        f"- one region, staged (bins 0.5 Hz apart on every 3rd subgrid point, refine, then exact levels for the"
        f" best candidates): p50 {h['region_screened_one_direction']['p50_ms']:.0f} ms wall,"
        f" {h['region_screened_one_direction']['cpu_p50_ms']:.0f} ms CPU; same actuator and frequency"
        f" (within 1 Hz) as exhaustive in"
        f" {h['screened_same_choice_fraction'] * 100:.0f} % of cases; its margin (active vs mirror side) is within"
        f" 0.5 dB of the exhaustive optimum for {h['screened_within_0p5_db_fraction'] * 100:.0f} % of parts, lost median"
        f" {h['screened_margin_loss_db_median']:.2f} dB, max {h['screened_margin_loss_db_max']:.2f} dB",
        f"- whole table at 1 cm steps ({h['whole_table_regions']} regions x 4 directions,"
        f" {h['whole_table_workers']} processes): {h['whole_table_s']:.1f} s"
        + (
            f" (extrapolated from {h['whole_table_regions_timed']} regions)"
            if h["whole_table_regions_timed"] < h["whole_table_regions"]
            else ""
        )
        + f" wall, {h['whole_table_cpu_s']:.1f} s CPU summed over processes (target < 60 s on 2 cores;"
        f" 1-minute load average during the run {h['load_average_1min']:.1f})",
        f"- share of regions with a valid flow, per direction: {h['whole_table_ok_fraction_by_direction']}",
        "",
        "![hand flow](hand_flow.png)",
        "",
    ]
    p = d / "vibration.md"
    p.write_text("\n".join(lines))
    return p
