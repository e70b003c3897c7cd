"""``haptable bench localisation``: how well each rendering method localises, played into
the plate twin (closed loop, not the map's prediction).

Methods: ``paper_tables`` (one actuator or PALL per part, paper Fig. 8),
``independent_patches`` (a complex amplitude per patch from the generalised
eigenproblem) and ``time_reversal`` (x = conj(h_active)). Each answers through the
registered effects (``flow.patch_drives`` / ``hand_flow.patch_drives``) with, per part, a
frequency and the drive of each patch PA..PD as a complex amplitude (1 V peak on the
strongest patch: the same peak voltage for every method).

How a drive is played: a part is the sine ``Im(x_p e^{i w t})`` on each patch under the
effects' linear ramps, from rest. The plate is linear, so one time simulation per
frequency of the complex drive ``u(t) = env(t) e^{i w t}`` through every mode
(exact first-order-hold discretisation, lfilter) gives
every real per-patch drive at that frequency: the response to ``Im(x_p u)`` is
``Im(Q x . Y)`` (the same first-order-hold modal filters as ``closed_loop``). What the twin then does at a point is measured as the flows' checks do:
the amplitude of the part's own frequency over the flat stretch after the ramp and
``settle_s`` (a lock-in, ``closed_loop.window_tone_um``). ``tests/closed_loop`` checks
this against the explicit (n, 4) drive and against the same flows played through the
safety gate (``loop_check.flow_pairs_check``).

Contrast of a pair part: 20 log10(active / passive) at the two grid points; under a hand:
strongest active square / strongest passive square (the paper's margin; squares at the
level at least half their 15 x 15 subgrid points reach) and weakest active / strongest
passive (``min_active``).
"""

from __future__ import annotations

import math
import time
from dataclasses import dataclass

import numpy as np

from console.plugin_api import UserError, machine_info
from console.plugin_api.runtime import open_outputs

from .closed_loop import (
    foh_filters,
    hand_subgrid_mm,
    lattice_shapes_um,
    point_shapes_um,
    square_levels_um,
    steady_window,
    twin_of,
)
from .loop_check import flow_pairs_check
from .loop_play import (
    DEFAULT_PAIRS,
    DEFAULT_REGIONS,
    LoopSettings,
    effects_of,
    measured_map,
    one_blas_thread,
    play_and_envelope,
)
from .model import Twin

METHODS = ("paper_tables", "independent_patches", "time_reversal")
#: the effects' names for the methods
EFFECT_METHOD = {
    "paper_tables": "paper",
    "independent_patches": "independent",
    "time_reversal": "time_reversal",
}
#: map error for the sensitivity runs: sigma / RMS |H| of the bin (complex Gaussian)
NOISE_LEVELS = (0.03, 0.1)


@dataclass(frozen=True)
class ToneLockin:
    """Lock-in of one part's steady stretch for the complex drive u = env e^{iwt}:
    (2,) cos/sin coefficients of Re and Im of each mode's response ``y_re``/``y_im``
    (R, 2), and of u itself (the residual rows) ``u_re``/``u_im`` (2,)."""

    freq_hz: float
    y_re: np.ndarray
    y_im: np.ndarray
    u_re: np.ndarray
    u_im: np.ndarray


def part_envelope(n: int, ramp_n: int) -> np.ndarray:
    """The effects' tone envelope: linear ramps of ``ramp_n`` samples at both ends."""
    env = np.ones(n)
    env[:ramp_n] = np.arange(ramp_n) / ramp_n
    env[-ramp_n:] = np.arange(ramp_n)[::-1] / ramp_n
    return env


_FILTERS: dict[tuple, list] = {}


def mode_filters(twin: Twin, fs_hz: float) -> list:
    """The twin's per-mode ``closed_loop.foh_filters`` at ``fs_hz`` (kept per twin, rate)."""
    key = (twin.key, float(fs_hz))
    if key not in _FILTERS:
        _FILTERS.clear()
        _FILTERS[key] = foh_filters(twin.modes.omega_rad_s, twin.params.damping_ratio, fs_hz)
    return _FILTERS[key]


def tone_lockin(twin: Twin, freq_hz: float, fs_hz: float, ls: LoopSettings) -> ToneLockin:
    """Simulate ``u`` through every mode from rest and lock in on its flat stretch."""
    from scipy.signal import lfilter

    n = int(round(ls.part_s * fs_hz))
    nr = max(1, int(round(ls.ramp_ms / 1e3 * fs_hz)))
    s, e = steady_window(0, n, fs_hz, ls.ramp_ms / 1e3, ls.settle_s)
    t = np.arange(e) / fs_hz
    u = part_envelope(n, nr)[:e] * np.exp(2j * np.pi * freq_hz * t)
    y = np.empty((twin.modes.omega_rad_s.size, e), complex)
    for r, (b, a) in enumerate(mode_filters(twin, fs_hz)):
        y[r] = lfilter(b, a, u)
    tw = t[s:e]
    basis = np.column_stack([np.cos(2 * np.pi * freq_hz * tw), np.sin(2 * np.pi * freq_hz * tw)])
    solve = np.linalg.solve(basis.T @ basis, basis.T)  # (2, m)
    ys, us = y[:, s:e], u[s:e]
    return ToneLockin(
        float(freq_hz),
        (solve @ ys.real.T).T,
        (solve @ ys.imag.T).T,
        solve @ us.real,
        solve @ us.imag,
    )


def tone_um_per_v(twin: Twin, lock: ToneLockin, shapes_um: np.ndarray, x: np.ndarray) -> np.ndarray:
    """Tone amplitude (um per volt of drive scale) at the points of ``shapes_um``
    (P, R + 4) for drives ``x``: (4,) for all points, or (P, 4) one per point."""
    x = np.asarray(x, complex)
    c = x @ twin.q[:, :4].T  # (R,) or (P, R)
    r = twin.q.shape[0]
    sm, sr = shapes_um[:, :r], shapes_um[:, r:]
    coef = (sm * c.real) @ lock.y_im + (sm * c.imag) @ lock.y_re
    coef += np.sum(sr * x.real, axis=-1)[:, None] * lock.u_im[None]
    coef += np.sum(sr * x.imag, axis=-1)[:, None] * lock.u_re[None]
    return np.hypot(coef[:, 0], coef[:, 1])


class Player:
    """Lock-ins per frequency, computed once and shared by every method and pair."""

    def __init__(self, twin: Twin, fs_hz: float, ls: LoopSettings) -> None:
        self.twin, self.fs, self.ls = twin, float(fs_hz), ls
        self._locks: dict[float, ToneLockin] = {}
        self.sim_s = 0.0

    def lock(self, freq_hz: float) -> ToneLockin:
        f = round(float(freq_hz), 6)
        if f not in self._locks:
            t0 = time.perf_counter()
            self._locks[f] = tone_lockin(self.twin, f, self.fs, self.ls)
            self.sim_s += time.perf_counter() - t0
        return self._locks[f]

    @property
    def frequencies(self) -> int:
        return len(self._locks)


def percentiles(values) -> dict:
    a = np.asarray([v for v in values if np.isfinite(v)], float)
    if a.size == 0:
        return {"n": 0}
    p10, p50, p90 = np.percentile(a, [10, 50, 90])
    return {"n": int(a.size), "p10": float(p10), "p50": float(p50), "p90": float(p90)}


# --------------------------------------------------------------------------- pairs
def play_pairs(player: Player, shapes_um: np.ndarray, pairs, answers: list[dict]) -> list[dict]:
    """Achieved active/passive tone (um) per answered pair (``None`` answers skipped)."""
    rows = []
    by_f: dict[float, list[int]] = {}
    for i, ans in enumerate(answers):
        if ans is not None:
            by_f.setdefault(round(float(ans["frequency_hz"]), 6), []).append(i)
    ach = {}
    for f, idx in by_f.items():
        lock = player.lock(f)
        pts = np.array([[pairs[i][0], pairs[i][1]] for i in idx])  # map indices
        x = np.array([answers[i]["weights"] for i in idx])
        act = tone_um_per_v(player.twin, lock, shapes_um[pts[:, 0]], x)
        pas = tone_um_per_v(player.twin, lock, shapes_um[pts[:, 1]], x)
        for j, i in enumerate(idx):
            ach[i] = (float(act[j]), float(pas[j]))
    for i, ans in enumerate(answers):
        if ans is None:
            rows.append({"pair": pairs[i], "ok": False})
            continue
        a, p = ach[i]
        v = float(ans["amplitude_v"])
        rows.append(
            {
                "pair": pairs[i],
                "ok": True,
                "frequency_hz": float(ans["frequency_hz"]),
                "amplitude_v": v,
                "peak_patch_v": v * float(np.abs(ans["weights"]).max()),
                "pred_contrast_db": float(ans["contrast_db"]),
                "ach_active_um": a * v,
                "ach_passive_um": p * v,
                "ach_contrast_db": 20 * math.log10(max(a, 1e-300) / max(p, 1e-300)),
                "ach_active_sl_db": 20 * math.log10(max(a * v, 1e-300))
                - float(ans["threshold_db"]),
            }
        )
    return rows


def pair_summary(rows: list[dict], cap_v: float) -> dict:
    ok = [r for r in rows if r["ok"]]
    return {
        "parts": len(rows),
        "no_flow": len(rows) - len(ok),
        "achieved_contrast_db": percentiles(r["ach_contrast_db"] for r in ok),
        "predicted_contrast_db": percentiles(r["pred_contrast_db"] for r in ok),
        "drive_v": percentiles(r["amplitude_v"] for r in ok),
        "at_cap_fraction": float(np.mean([r["amplitude_v"] >= cap_v - 1e-9 for r in ok]))
        if ok
        else float("nan"),
        "active_sl_db": percentiles(r["ach_active_sl_db"] for r in ok),
    }


# --------------------------------------------------------------------------- regions
def play_region(player: Player, center_mm, direction: str, parts: list[dict], hand_geo: dict,
                sides) -> list[dict]:  # fmt: skip
    """Achieved square levels for the parts of one hand flow (um per volt x amplitude)."""
    hand_mm, squares, subgrid = hand_geo["hand_mm"], hand_geo["squares"], hand_geo["subgrid"]
    xs, ys = hand_subgrid_mm(center_mm, hand_mm, squares, subgrid)
    shapes = lattice_shapes_um(player.twin, xs, ys)
    start, end = sides
    out = []
    for i, p in enumerate(parts):
        side_a, side_b = (start, end) if i == 0 else (end, start)
        amp = tone_um_per_v(player.twin, player.lock(p["frequency_hz"]), shapes, p["weights"])
        lv = square_levels_um(amp, squares, subgrid) * float(p["amplitude_v"])
        la, lb = lv[side_a], lv[side_b]
        out.append(
            {
                "region": f"{center_mm[0]:g},{center_mm[1]:g}",
                "direction": direction,
                "part": i + 1,
                "ok": True,
                "frequency_hz": float(p["frequency_hz"]),
                "amplitude_v": float(p["amplitude_v"]),
                "pred_contrast_db": float(p.get("contrast_db", p.get("margin_db", math.nan))),
                "ach_contrast_db": 20 * math.log10(la.max() / max(lb.max(), 1e-300)),
                "ach_min_active_db": 20 * math.log10(max(la.min(), 1e-300) / max(lb.max(), 1e-300)),
                "active_felt": bool(la.max() >= p["x_um"]),
                "passive_felt": bool(lb.max() >= p["x_um"]),
            }
        )
    return out


def region_summary(rows: list[dict], cap_v: float) -> dict:
    ok = [r for r in rows if r["ok"]]
    return {
        "parts": len(rows),
        "no_flow": len(rows) - len(ok),
        "achieved_contrast_db": percentiles(r["ach_contrast_db"] for r in ok),
        "achieved_min_active_db": percentiles(r["ach_min_active_db"] for r in ok),
        "predicted_contrast_db": percentiles(r["pred_contrast_db"] for r in ok),
        "drive_v": percentiles(r["amplitude_v"] for r in ok),
        "at_cap_fraction": float(np.mean([r["amplitude_v"] >= cap_v - 1e-9 for r in ok]))
        if ok
        else float("nan"),
        "active_felt_fraction": float(np.mean([r["active_felt"] for r in ok])) if ok else 0.0,
        "passive_felt_fraction": float(np.mean([r["passive_felt"] for r in ok])) if ok else 0.0,
    }


def noisy_map(m, rel: float, seed: int = 0):
    """The map plus circular complex Gaussian error on every FRF entry, std ``rel`` x
    the bin's RMS |H| over excitations and points (masked bins stay 0)."""
    from dataclasses import replace

    rng = np.random.default_rng(seed)
    h = m.frf_um_per_v
    rms = np.sqrt(np.mean(np.abs(h) ** 2, axis=(0, 1)))  # (F,)
    noise = (rng.standard_normal(h.shape) + 1j * rng.standard_normal(h.shape)) / math.sqrt(2)
    frf = h + rel * rms * noise
    frf[..., m.masked] = 0.0
    return replace(m, frf_um_per_v=frf, provenance={**m.provenance, "noise_rel": rel})


# --------------------------------------------------------------------------- bench
def grid_pairs(n_points: int, quick: bool, seed: int = 0) -> list[tuple[int, int]]:
    """Every ordered pair of map indices, or (quick) 150 of them at random."""
    allp = [(a, b) for a in range(n_points) for b in range(n_points) if a != b]
    if not quick:
        return allp
    rng = np.random.default_rng(seed)
    return [allp[i] for i in sorted(rng.choice(len(allp), 150, replace=False))]


def run_bench(ctx, quick: bool) -> dict:
    """``haptable bench localisation``: see the module docstring."""
    profile, pm = ctx.profile, ctx.pm
    t_all = time.perf_counter()
    ls = LoopSettings()
    with one_blas_thread():
        vmap = measured_map(profile, pm)
        flow, hand = effects_of(profile, pm, ls)
        twin = twin_of(profile)
        cap = float(flow.setup.cap_v)
        player = Player(twin, float(profile.get("audio.sample_rate_hz")), ls)
        shapes = point_shapes_um(twin, vmap.points_mm)
        pairs = grid_pairs(vmap.points.size, quick)
        res: dict = {
            "machine": machine_info(),
            "quick": quick,
            "part_s": ls.part_s,
            "cap_v": cap,
            "map_error_rel": float(flow.setup.map_error_rel),
            "how": "each part played from rest into the plate twin (exact modal time "
            "response of the per-patch drive, lock-in at the part's frequency over the flat "
            "stretch); contrast = active / passive amplitude, same peak volts per patch",
        }
        pair_rows: dict = {}
        res["pairs"] = {"n": len(pairs), "methods": {}}
        for meth in METHODS:
            t0 = time.perf_counter()
            ans = flow.patch_drives(pairs, vmap=vmap, method=EFFECT_METHOD[meth])
            t_solve = time.perf_counter() - t0
            t0 = time.perf_counter()
            rows = play_pairs(player, shapes, pairs, ans)
            pair_rows[meth] = rows
            res["pairs"]["methods"][meth] = {
                **pair_summary(rows, cap),
                "solve_s": t_solve,
                "play_s": time.perf_counter() - t0,
            }
        res["regions"] = _regions(player, hand, vmap, quick, cap)
        res["map_error"] = _sensitivity(player, flow, shapes, vmap, pairs, quick, cap)
        res["gate_check"] = _gate_check(profile, pm, flow, vmap, player, shapes, ls)
    pm_ = res["pairs"]["methods"]
    paper = pm_["paper_tables"]["achieved_contrast_db"]["p50"]
    ind = pm_["independent_patches"]["achieved_contrast_db"]["p50"]
    rp = res["regions"]["methods"]
    res["goal"] = {
        "target_db_above_paper": 6.0,
        "pairs_median_gain_db": ind - paper,
        "regions_median_gain_db": rp["independent_patches"]["achieved_contrast_db"].get(
            "p50", float("nan")
        )
        - rp["paper_tables"]["achieved_contrast_db"].get("p50", float("nan")),
    }
    res["goal"]["regions_median_min_active_gain_db"] = rp["independent_patches"][
        "achieved_min_active_db"
    ].get("p50", float("nan")) - rp["paper_tables"]["achieved_min_active_db"].get(
        "p50", float("nan")
    )
    res["goal"]["met"] = bool(
        res["goal"]["pairs_median_gain_db"] >= 6.0 and res["goal"]["regions_median_gain_db"] >= 6.0
    )
    res["frequencies_simulated"] = player.frequencies
    res["simulation_s"] = player.sim_s
    res["total_s"] = time.perf_counter() - t_all
    res["table"] = format_table(res)
    return res


def _regions(player: Player, hand, vmap, quick: bool, cap: float) -> dict:
    centers = list(DEFAULT_REGIONS[:2]) if quick else hand.region_centers(60.0, vmap=vmap)
    dirs = ("right", "up") if quick else ("left", "right", "up", "down")
    geo = dict(hand.setup.hand)
    out: dict = {"centers": len(centers), "directions": list(dirs), "methods": {}}
    for meth in METHODS:
        rows, t0 = [], time.perf_counter()
        for c in centers:
            for d in dirs:
                try:
                    parts = hand.patch_drives(c, d, vmap=vmap, method=EFFECT_METHOD[meth])
                except UserError as exc:
                    rows += [{"region": f"{c[0]:g},{c[1]:g}", "direction": d, "ok": False,
                              "reason": str(exc)}] * 2  # fmt: skip
                    continue
                rows += play_region(player, c, d, parts, geo, hand.sides(d))
        out["methods"][meth] = {**region_summary(rows, cap), "s": time.perf_counter() - t0}
    return out


def _sensitivity(player, flow, shapes, vmap, pairs, quick: bool, cap: float) -> dict:
    """Solve on a noisy map, play on the true plate."""
    levels = NOISE_LEVELS[1:] if quick else NOISE_LEVELS
    sub = pairs if quick else pairs[:: max(1, len(pairs) // 600)]
    out: dict = {
        "noise_model": "circular complex Gaussian added to every FRF entry of the measured "
        "map, std = rel x the bin's RMS |H| over excitations and points; the methods solve "
        "on it and play on the true plate",
        "pairs": len(sub),
        "levels": {},
    }
    for rel in levels:
        nm = noisy_map(vmap, rel, seed=1)
        row = {}
        for meth in METHODS:
            ans = flow.patch_drives(sub, vmap=nm, method=EFFECT_METHOD[meth])
            rows = play_pairs(player, shapes, sub, ans)
            row[meth] = pair_summary(rows, cap)["achieved_contrast_db"]
        out["levels"][f"{rel:g}"] = row
    return out


def _gate_check(profile, pm, flow, vmap, player, shapes, ls) -> dict:
    """The paper's flows of the first default pairs played through the safety gate
    (``flow_pairs_check``), and the independent flows of the same pairs played through
    the gate with a channel per patch (``independent``), against the same parts played
    here: contrast difference."""
    pairs_no = DEFAULT_PAIRS[:2]
    tables = flow.tables(vmap=vmap, rule="paper")
    with open_outputs(profile, pm, fast=True) as out:
        gate = flow_pairs_check(out, profile, tables, pairs_no, ls, plugins=pm, ringdown_gap_k=0)
    idx = [(vmap.point_index(r["active"]), vmap.point_index(r["passive"])) for r in gate]
    mine = play_pairs(player, shapes, idx, flow.patch_drives(idx, vmap=vmap, method="paper"))
    diff = [
        abs(g["ach_contrast_db"] - m["ach_contrast_db"]) for g, m in zip(gate, mine, strict=True)
    ]
    rows = independent_through_gate(per_patch_profile(profile), pm, vmap, pairs_no, ls, player)
    return {
        "parts": len(gate),
        "max_contrast_difference_db": float(max(diff)),
        "gate_contrast_db": [float(g["ach_contrast_db"]) for g in gate],
        "here_contrast_db": [float(m["ach_contrast_db"]) for m in mine],
        "independent": {
            "channels": ["PA", "PB", "PC", "PD", "screen"],
            "max_contrast_difference_db": float(
                max(abs(r["gate_contrast_db"] - r["here_contrast_db"]) for r in rows)
            ),
            "rows": rows,
        },
    }


def per_patch_profile(profile):
    """The profile with a channel per patch (``[audio] channels`` = PA..PD, screen)."""
    from dataclasses import replace

    audio = {**profile.section("audio"), "channels": ["PA", "PB", "PC", "PD", "screen"]}
    return replace(profile, data={**profile.data, "audio": audio})


def independent_through_gate(profile4, pm, vmap, pairs_no, ls, player) -> list[dict]:
    """Independent flows between grid numbers played through the safety gate on a
    per-patch profile, recorded, then into the plate twin; per part the achieved
    contrast there and here (the same answer played by ``play_pairs``)."""
    flow4, _ = effects_of(profile4, pm, ls)
    shapes = point_shapes_um(player.twin, vmap.points_mm)
    rows = []
    with open_outputs(profile4, pm, fast=True) as out:
        for a_no, b_no in pairs_no:
            plan = flow4.render(int(a_no), int(b_no), vmap=vmap, method="independent")
            pts = np.array([plan.meta["from_mm"], plan.meta["to_mm"]])
            freqs = [p["frequency_hz"] for p in plan.meta["parts"]]
            env = play_and_envelope(out, profile4, player.twin, plan, pts, ls, 2, freqs)
            a, b = vmap.point_index(a_no), vmap.point_index(b_no)
            pair = [(a, b), (b, a)]
            here = play_pairs(
                player, shapes, pair, flow4.patch_drives(pair, vmap=vmap, method="independent")
            )
            for i, (e, h) in enumerate(zip(env, here, strict=True)):
                act, pas = (0, 1) if i == 0 else (1, 0)
                amp = plan.meta["parts"][i]["amplitude_v"]
                rows.append(
                    {
                        "pair": f"{a_no}->{b_no}",
                        "part": i + 1,
                        "frequency_hz": float(freqs[i]),
                        "gate_contrast_db": 20
                        * math.log10(float(e.tone_um[act]) / max(float(e.tone_um[pas]), 1e-300)),
                        "here_contrast_db": float(h["ach_contrast_db"]),
                        "gate_active_um_per_v": float(e.tone_um[act]) / amp,
                        "here_active_um_per_v": h["ach_active_um"] / h["amplitude_v"],
                    }
                )
    return rows


def format_table(res: dict) -> list[str]:
    """One line per method: pair and region contrast p10/p50/p90, drive volts, noise."""
    out = [
        f"{'method':>20} {'pairs dB p10/p50/p90':>22} {'hand dB p10/p50/p90':>22} "
        f"{'V p50/p90':>11} {'at cap':>6} "
        + " ".join(f"{'noise ' + k + ' p50':>12}" for k in res["map_error"]["levels"])
    ]
    for meth in METHODS:
        p = res["pairs"]["methods"][meth]
        r = res["regions"]["methods"][meth]
        c, h, v = p["achieved_contrast_db"], r["achieved_contrast_db"], p["drive_v"]
        hs = f"{h['p10']:6.1f}/{h['p50']:6.1f}/{h['p90']:6.1f}" if h.get("n") else "-"
        noise = " ".join(
            f"{lv[meth].get('p50', float('nan')):12.1f}"
            for lv in res["map_error"]["levels"].values()
        )
        out.append(
            f"{meth:>20} {c['p10']:6.1f}/{c['p50']:6.1f}/{c['p90']:6.1f}   {hs:>22} "
            f"{v['p50']:5.1f}/{v['p90']:5.1f} {p['at_cap_fraction']:6.2f} {noise}"
        )
    return out
