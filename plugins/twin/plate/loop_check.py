"""Closed-loop check: flows rendered from a measured map, played through the safety gate,
and the plate twin's true response to what was played, against what the tables predicted.

Used by ``tests/closed_loop`` and the ``closed-loop`` benchmark. The stimuli come from the
registered effects ``flow`` and ``hand_flow`` (``plugins.get("effect", name)``: this is a
consumer of their plans, exactly as a scene is); the outputs are the profile's (twin
audio + relays), so every sample went through ``console.safety``. The effects' options
are checked here too: ``min_contrast_db`` (contrast-aware tables) and
``ringdown_gap_k`` (silence of k decay times after part 1); ``compare_options`` plays
the same pairs and regions with the paper's rule and with the options.

Per flow part the table predicts, at drive amplitude V and the part's frequency/actuator,
active = V |H_active|, passive = V |H_passive| and margin = V x (table difference). The
twin gives the steady amplitude (sqrt 2 x RMS over the flat stretch after the ramp and
``settle_s``) at the same points from the RECORDING and the relay log. Under a hand the
same is done for the 3 x 3 squares (level = the value at least half of a square's 15 x 15
subgrid points reach) against the 3-JND line X(f) of the palm.
"""

from __future__ import annotations

import math
import time
from dataclasses import dataclass

import numpy as np

from console.channels import ChannelLayout

from .closed_loop import (
    drive_from_recording,
    hand_subgrid_mm,
    part_envelopes,
    square_levels_um,
    twin_of,
)

#: Pairs (grid numbers, active -> passive) checked by default: the paper's 51/52 example
#: both ways, diagonal neighbours as in Fig. 10's pairs 1-1, 3-3, 4-4, and a long pair.
DEFAULT_PAIRS: tuple[tuple[int, int], ...] = (
    (51, 52),
    (52, 51),
    (27, 40),
    (40, 27),
    (62, 75),
    (19, 32),
    (14, 71),
)
#: Hand regions (centre mm): four spots across the table (the paper's R1..R4 are only
#: drawn, not given in numbers), each with the four directions.
DEFAULT_REGIONS: tuple[tuple[float, float], ...] = (
    (180.0, 280.0),
    (300.0, 160.0),
    (460.0, 290.0),
    (580.0, 150.0),
)


@dataclass(frozen=True)
class LoopSettings:
    part_s: float = 1.5
    ramp_ms: float = 100.0
    settle_s: float = 0.2  # after the ramp before the steady stretch (lowest mode's tau)
    pre_s: float = 0.05  # recording kept before the first part (plate at rest)


def measured_map(profile, plugins=None, progress=None):
    """The profile's vibration map measured by its ``[vibrometer] driver`` (twin default)."""
    from console.vibration_map import make_map

    name = str(profile.get("vibrometer.driver", "twin"))
    if plugins is None:
        from .vibrometer import TwinVibrometer

        dev = TwinVibrometer(profile)
    else:
        dev = plugins.get("vibrometer", name).factory(profile)
    out = dev.measure(progress=progress)
    return make_map(**{k: v for k, v in out.items() if k != "meta"})


def relay_channels_of(profile) -> dict[str, int]:
    return {
        n: int(p["relay_channel"])
        for n, p in profile.items("patches").items()
        if p.get("relay_channel")
    }


def loop_profile(profile, ls: LoopSettings):
    """The profile with the flow parts' length and ramp of ``ls`` (``[vibrotactile]
    part_s`` / ``ramp_ms``); everything else as the profile says."""
    from dataclasses import replace

    vt = {**profile.section("vibrotactile"), "part_s": ls.part_s, "ramp_ms": ls.ramp_ms}
    return replace(profile, data={**profile.data, "vibrotactile": vt})


def effects_of(profile, plugins=None, ls: LoopSettings | None = None) -> tuple:
    """The registered ``flow`` and ``hand_flow`` effects for ``profile`` with ``ls``'s
    part length (``plugins`` default: the installed plugins)."""
    if plugins is None:
        from console.plugins import load_plugins

        plugins = load_plugins()
    prof = loop_profile(profile, ls or LoopSettings())
    return (
        plugins.get("effect", "flow").factory(prof),
        plugins.get("effect", "hand_flow").factory(prof),
    )


def recording_with_offset(outputs, tries: int = 200) -> tuple[np.ndarray, int]:
    """The outputs' recording and the clock of its first sample.

    The twin keeps the last ``record_s`` seconds; the clock of its first sample is
    (blocks played x block size) - its length, read when the outputs are idle and the
    block count is stable around the read.
    """
    if outputs.recording() is None:
        from console.errors import UserError

        raise UserError(
            "closed loop: these outputs record nothing (real hardware); use a profile whose "
            "[audio] driver is the twin"
        )
    for _ in range(tries):
        time.sleep(0.002)
        st = outputs.status()
        if st["busy"]:
            continue
        b1 = st["audio"].get("blocks")
        rec = outputs.recording()
        b2 = outputs.status()["audio"].get("blocks")
        if b1 is not None and b1 == b2:
            return rec, int(b1) * int(st["audio"]["block_size"]) - rec.shape[0]
    raise RuntimeError("outputs never went idle: cannot align the recording with its clock")


def _play_and_envelope(
    outputs, profile, twin, plan, points_mm, ls: LoopSettings, peak_points, freqs_hz
):
    """Play ``plan`` through the gate, then the twin's envelopes per part at the points."""
    report = outputs.play(plan)
    fs = plan.sample_rate_hz
    start = max(0, report.segment_start[0] - int(ls.pre_s * fs))
    stop = report.segment_end[-1] + int(0.5 * fs)
    rec, clock0 = recording_with_offset(outputs)
    v, w = drive_from_recording(
        rec,
        outputs.relay_log(),
        relay_channels_of(profile),
        start,
        stop,
        clock0,
        ChannelLayout.from_profile(profile).names,
    )
    parts = [
        (s - start, e - start)
        for s, e in zip(report.segment_start, report.segment_end, strict=True)
    ]
    return part_envelopes(
        twin,
        v,
        w,
        points_mm,
        fs,
        parts,
        ramp_s=ls.ramp_ms / 1e3,
        settle_s=ls.settle_s,
        freqs_hz=freqs_hz,
        peak_points=peak_points,
    )


def flow_pairs_check(
    outputs,
    profile,
    tables,
    pairs=DEFAULT_PAIRS,
    ls: LoopSettings | None = None,
    *,
    plugins=None,
    min_contrast_db: float | None = None,
    ringdown_gap_k: float | None = None,
) -> list[dict]:
    """One row per (pair, part): predicted vs achieved active/passive amplitude and margin.

    ``tables``: lookup tables (used as they are) or a vibration map (tables built by the
    ``flow`` effect with ``min_contrast_db``, default the profile's). ``ringdown_gap_k``:
    the effect's ring-down gap (default the profile's). Achieved = the part's tone
    amplitude on the twin (``tone_um``); the rows also carry the broadband level
    (``all_*``: the previous part's ring-down included) and the passive point's level
    while the part ramps up (``onset_passive_um``)."""
    with _one_blas_thread():
        return _flow_pairs_check(
            outputs, profile, tables, pairs, ls, plugins, min_contrast_db, ringdown_gap_k
        )


def _one_blas_thread():
    """Thin matrix products throughout: one BLAS thread is fastest (and on a loaded
    2-core machine, multi-threaded BLAS is 10x slower)."""
    from threadpoolctl import threadpool_limits

    return threadpool_limits(limits=1, user_api="blas")


def _source(tables, min_contrast_db) -> dict:
    """Render request keys for a tables-or-map argument."""
    vmap = getattr(tables, "vmap", None)
    if vmap is None:  # a map
        return {"vmap": tables, "min_contrast_db": min_contrast_db}
    if min_contrast_db is not None and min_contrast_db != tables.min_contrast_db:
        return {"vmap": vmap, "min_contrast_db": min_contrast_db}
    return {"tables": tables}


def _flow_pairs_check(
    outputs, profile, tables, pairs, ls, plugins, min_contrast_db, ringdown_gap_k
) -> list[dict]:
    ls = ls or LoopSettings()
    twin = twin_of(profile)
    flow, _ = effects_of(profile, plugins, ls)
    src = _source(tables, min_contrast_db)
    rows = []
    for a_no, b_no in pairs:
        plan = flow.render(
            from_point=int(a_no), to_point=int(b_no), ringdown_gap_k=ringdown_gap_k, **src
        )
        pts = np.array([plan.meta["from_mm"], plan.meta["to_mm"]])
        freqs = [p["frequency_hz"] for p in plan.meta["parts"]]
        env = _play_and_envelope(outputs, profile, twin, plan, pts, ls, 2, freqs)
        for i, (p, e) in enumerate(zip(plan.meta["parts"], env, strict=True)):
            act, pas = (0, 1) if i == 0 else (1, 0)
            v = p["amplitude_v"]
            pred_a, pred_p = v * p["active_um_per_v"], v * p["passive_um_per_v"]
            ach_a, ach_p = float(e.tone_um[act]), float(e.tone_um[pas])
            thr_db = float(p["threshold_db"])  # fingertip threshold at the part's frequency
            rows.append(
                {
                    "pair": f"{a_no}->{b_no}",
                    "part": i + 1,
                    "active": (a_no, b_no)[act],
                    "passive": (a_no, b_no)[pas],
                    "actuator": p["actuator"],
                    "frequency_hz": p["frequency_hz"],
                    "amplitude_v": v,
                    "gap_s": float(plan.gap_s),
                    "min_contrast_db": float(plan.meta.get("min_contrast_db", 0.0)),
                    "table_um_per_v": p["max_difference_um_per_v"],
                    "pred_active_um": pred_a,
                    "pred_passive_um": pred_p,
                    "pred_margin_um": v * p["max_difference_um_per_v"],
                    "pred_contrast_db": float(p["contrast_db"]),
                    "ach_active_um": ach_a,
                    "ach_passive_um": ach_p,
                    "ach_margin_um": ach_a - ach_p,
                    "ach_contrast_db": 20 * math.log10(ach_a / max(ach_p, 1e-30)),
                    "ach_active_sl_db": 20 * math.log10(max(ach_a, 1e-30)) - thr_db,
                    "ach_passive_sl_db": 20 * math.log10(max(ach_p, 1e-30)) - thr_db,
                    "all_active_um": float(e.amplitude_um[act]),
                    "all_passive_um": float(e.amplitude_um[pas]),
                    "onset_passive_um": float(e.onset_um[pas]),
                    "onset_passive_sl_db": 20 * math.log10(max(float(e.onset_um[pas]), 1e-30))
                    - thr_db,
                    "peak_active_um": float(e.peak_um[act]),
                    "peak_passive_um": float(e.peak_um[pas]),
                    "margin_error_rel_active": abs(
                        (ach_a - ach_p) - v * p["max_difference_um_per_v"]
                    )
                    / max(pred_a, 1e-12),
                }
            )
    return rows


def hand_regions_check(
    outputs,
    profile,
    vmap,
    regions=DEFAULT_REGIONS,
    directions=("left", "right", "up", "down"),
    ls: LoopSettings | None = None,
    screen_stride: int = 3,
    *,
    plugins=None,
    ringdown_gap_k: float | None = None,
) -> list[dict]:
    """One row per (region, direction, part): square levels predicted from the map vs
    achieved on the twin, against the 3-JND line; a flow the map cannot make is a row
    with ``ok`` False and its reason. ``screen_stride`` as in ``haptable flow --hand``
    (3: staged search; 1: exhaustive). ``ringdown_gap_k``: the effect's ring-down gap
    (default the profile's). Regions are rendered at their centre rounded to 0.1 mm."""
    with _one_blas_thread():
        return _hand_regions_check(
            outputs, profile, vmap, regions, directions, ls, screen_stride, plugins, ringdown_gap_k
        )


def _hand_regions_check(
    outputs, profile, vmap, regions, directions, ls, screen_stride, plugins, ringdown_gap_k
):
    from console.errors import UserError

    ls = ls or LoopSettings()
    twin = twin_of(profile)
    _, hand = effects_of(profile, plugins, ls)
    vt = profile.section("vibrotactile")
    hand_mm, squares, subgrid = (
        float(vt.get("hand_mm", 120.0)),
        int(vt.get("hand_squares", 3)),
        int(vt.get("hand_subgrid", 15)),
    )
    rows = []
    for c in regions:
        for d in directions:
            base = {"region": f"{c[0]:g},{c[1]:g}", "direction": d}
            try:
                plan = hand.render(
                    center_mm=c,
                    direction=d,
                    vmap=vmap,
                    exhaustive=screen_stride == 1,
                    screen_stride=screen_stride,
                    ringdown_gap_k=ringdown_gap_k,
                )
            except UserError as exc:
                rows.append({**base, "part": 0, "ok": False, "reason": str(exc)})
                continue
            center = tuple(plan.meta["center_mm"])
            pts = hand_subgrid_mm(center, hand_mm, squares, subgrid)  # lattice (xs, ys)
            parts = plan.meta["parts"]
            freqs = [p["frequency_hz"] for p in parts]
            env = _play_and_envelope(outputs, profile, twin, plan, pts, ls, 0, freqs)
            start, end = hand.sides(d)
            for i, (p, e) in enumerate(zip(parts, env, strict=True)):
                side_a, side_b = (start, end) if i == 0 else (end, start)
                v, x = p["amplitude_v"], p["x_um"]
                q = hand.square_levels_um_per_v(center, p["actuator"], p["frequency_hz"], vmap=vmap)
                pred = q * v
                ach = square_levels_um(e.tone_um, squares, subgrid)
                ach_all = square_levels_um(e.amplitude_um, squares, subgrid)
                onset = square_levels_um(e.onset_um, squares, subgrid)
                rows.append(
                    {
                        **base,
                        "part": i + 1,
                        "ok": True,
                        "actuator": p["actuator"],
                        "frequency_hz": p["frequency_hz"],
                        "amplitude_v": v,
                        "gap_s": float(plan.gap_s),
                        "x_um": x,
                        "pred_active_um": float(pred[side_a].max()),
                        "pred_passive_um": float(pred[side_b].max()),
                        "pred_margin_db": p["margin_db"],
                        "ach_active_um": float(ach[side_a].max()),
                        "ach_passive_um": float(ach[side_b].max()),
                        "ach_margin_db": float(
                            20 * math.log10(ach[side_a].max() / max(ach[side_b].max(), 1e-30))
                        ),
                        "pred_active_squares": (pred >= x).astype(int).tolist(),
                        "ach_active_squares": (ach >= x).astype(int).tolist(),
                        "all_passive_um": float(ach_all[side_b].max()),
                        "onset_passive_um": float(onset[side_b].max()),
                        "ach_passive_side_felt": bool(ach[side_b].max() >= x),
                        "all_passive_side_felt": bool(ach_all[side_b].max() >= x),
                        "onset_passive_side_felt": bool(onset[side_b].max() >= x),
                        "ach_active_side_felt": bool(ach[side_a].max() >= x),
                        "level_error_db": float(
                            np.max(np.abs(20 * np.log10(np.maximum(ach, 1e-30) / pred)))
                        ),
                    }
                )
    return rows


def verdict(row: dict) -> str:
    """What a user would notice for one hand-flow part (first problem found).

    ``BOTH SIDES``: the passive side reaches the 3-JND line at the part's own frequency
    (the map's interpolation was wrong there); ``BOTH SIDES (ring-down)``: in the flat
    stretch the passive side reaches it through what still rings from the previous
    part; ``overlap at onset``: while this part ramps up the passive side (the previous
    part's active side) still vibrates above the line; ``active side not felt``.
    """
    if not row["ok"]:
        return "no flow"
    if not row["ach_active_side_felt"]:
        return "active side not felt"
    if row["ach_passive_side_felt"]:
        return "BOTH SIDES"
    if row["all_passive_side_felt"]:
        return "BOTH SIDES (ring-down)"
    if row["onset_passive_side_felt"]:
        return "overlap at onset"
    return "ok"


def format_pairs(rows: list[dict]) -> str:
    head = (
        f"{'pair':>7} {'pt':>2} {'act':>4} {'f_Hz':>6} {'V':>6} {'gap s':>5} "
        f"{'pred A/P um':>15} {'ach A/P um':>15} {'pred dA':>7} {'ach dA':>7} {'err%':>5} "
        f"{'all P um':>8} {'onset P':>7} {'dB A/P':>6} {'SL P dB':>7}"
    )
    out = [head]
    for r in rows:
        out.append(
            f"{r['pair']:>7} {r['part']:>2} {r['actuator']:>4} {r['frequency_hz']:6.1f} "
            f"{r['amplitude_v']:6.2f} {r.get('gap_s', 0.0):5.3f} "
            f"{r['pred_active_um']:7.3f}/{r['pred_passive_um']:<7.3f} "
            f"{r['ach_active_um']:7.3f}/{r['ach_passive_um']:<7.3f} "
            f"{r['pred_margin_um']:7.3f} {r['ach_margin_um']:7.3f} "
            f"{100 * r['margin_error_rel_active']:5.1f} "
            f"{r['all_passive_um']:8.3f} {r['onset_passive_um']:7.3f} "
            f"{r['ach_contrast_db']:6.1f} {r['ach_passive_sl_db']:7.1f}"
        )
    return "\n".join(out)


def format_regions(rows: list[dict]) -> str:
    head = (
        f"{'region':>7} {'dir':>5} {'pt':>2} {'act':>4} {'f_Hz':>6} {'V':>6} {'X um':>5} "
        f"{'pred A/B um':>11} {'ach A/B um':>11} {'pred dB':>7} {'ach dB':>6} "
        f"{'all B':>5} {'onsetB':>6} verdict"
    )
    out = [head]
    for r in rows:
        if not r["ok"]:
            out.append(f"{r['region']:>7} {r['direction']:>5}  - no flow: {r['reason']}")
            continue
        out.append(
            f"{r['region']:>7} {r['direction']:>5} {r['part']:>2} {r['actuator']:>4} "
            f"{r['frequency_hz']:6.1f} {r['amplitude_v']:6.2f} {r['x_um']:5.3f} "
            f"{r['pred_active_um']:5.3f}/{r['pred_passive_um']:<5.3f} "
            f"{r['ach_active_um']:5.3f}/{r['ach_passive_um']:<5.3f} "
            f"{r['pred_margin_db']:7.1f} {r['ach_margin_db']:6.1f} "
            f"{r['all_passive_um']:5.3f} {r['onset_passive_um']:6.3f} {verdict(r)}"
        )
    return "\n".join(out)


def summarize(pairs: list[dict], regions: list[dict]) -> dict:
    """Headline numbers: pair margin errors, hand-flow verdict counts and margin errors."""
    out: dict = {}
    if pairs:
        err = [100 * r["margin_error_rel_active"] for r in pairs]
        out["pairs_margin_error_pct_of_active"] = {"median": float(np.median(err)), "max": max(err)}
        out["pairs_low_contrast"] = [
            f"{r['pair']} part {r['part']} ({r['frequency_hz']:g} Hz, "
            f"{r['ach_contrast_db']:.1f} dB, passive {r['ach_passive_sl_db']:.0f} dB SL)"
            for r in pairs
            if r["ach_contrast_db"] < 3.0
        ]
        out["pairs_ringdown_overlap"] = [
            f"{r['pair']} part {r['part']}"
            for r in pairs
            if r["part"] == 2 and r["onset_passive_um"] > 1.5 * r["all_passive_um"]
        ]
    ok = [r for r in regions if r["ok"]]
    counts: dict[str, int] = {}
    for r in regions:
        counts[verdict(r)] = counts.get(verdict(r), 0) + 1
    out["region_parts"] = len(regions)
    out["region_verdicts"] = counts
    if ok:
        d = [r["ach_margin_db"] - r["pred_margin_db"] for r in ok]
        out["region_margin_error_db"] = {
            "median": float(np.median(d)),
            "worst": float(min(d)),
            "best": float(max(d)),
        }
        out["region_worst_square_level_error_db"] = float(max(r["level_error_db"] for r in ok))
    return out


#: The options ``compare_options`` turns on (suggested values, not the defaults): a
#: 10 dB contrast floor keeps the passive point 10 dB below the active one (first-mode
#: entries at ~2 dB never win); 3 decay times of silence put part 1's ring 26 dB down.
OPTION_CONTRAST_DB = 10.0
OPTION_RINGDOWN_K = 3.0
#: Hand regions for the comparison: where the whole-table scan (60 mm steps) found part 1
#: ringing into part 2 above the 3-JND line, and the right edge (low headroom).
OPTION_REGIONS: tuple[tuple[float, float], ...] = ((281.73, 223.645), (641.73, 163.645))


def pair_problems(rows: list[dict]) -> dict:
    """The two reported pair failures, counted: parts with < 3 dB achieved contrast, and
    parts 2 that start with the passive point still ringing from part 1 (onset level >
    1.5 x its flat-stretch level)."""
    low = [r for r in rows if r["ach_contrast_db"] < 3.0]
    ring = [r for r in rows if r["part"] == 2 and r["onset_passive_um"] > 1.5 * r["all_passive_um"]]
    return {
        "low_contrast": [f"{r['pair']} part {r['part']}" for r in low],
        "ringdown_overlap": [f"{r['pair']} part {r['part']}" for r in ring],
        "min_contrast_db": float(min(r["ach_contrast_db"] for r in rows)),
        "max_passive_sl_db": float(max(r["ach_passive_sl_db"] for r in rows)),
        "max_onset_passive_sl_db": float(max(r["onset_passive_sl_db"] for r in rows)),
        "max_gap_s": float(max(r["gap_s"] for r in rows)),
    }


def compare_options(
    outputs,
    profile,
    vmap,
    pairs=DEFAULT_PAIRS,
    regions=DEFAULT_REGIONS,
    directions=("left", "right", "up", "down"),
    *,
    plugins=None,
    min_contrast_db: float = OPTION_CONTRAST_DB,
    ringdown_gap_k: float = OPTION_RINGDOWN_K,
    ls: LoopSettings | None = None,
) -> dict:
    """The same flows with the paper's rule (``min_contrast_db`` 0, no ring-down gap)
    and with the options, played through the gate into the twin: per setting the pair
    rows and problems, the region verdict counts (hand flows only take the gap)."""
    settings = {
        "paper": (0.0, 0.0),
        "ringdown_gap": (0.0, ringdown_gap_k),
        "contrast_floor": (min_contrast_db, 0.0),
        "both": (min_contrast_db, ringdown_gap_k),
    }
    out: dict = {"min_contrast_db": min_contrast_db, "ringdown_gap_k": ringdown_gap_k}
    for name, (c, k) in settings.items():
        rows = flow_pairs_check(
            outputs, profile, vmap, pairs, ls, plugins=plugins, min_contrast_db=c, ringdown_gap_k=k
        )
        out[name] = {"pairs": rows, "pair_problems": pair_problems(rows)}
    if regions:
        for name, k in (("paper", 0.0), ("ringdown_gap", ringdown_gap_k)):
            rows = hand_regions_check(
                outputs, profile, vmap, regions, directions, ls, plugins=plugins, ringdown_gap_k=k
            )
            out[name]["regions"] = rows
            out[name]["region_verdicts"] = summarize([], rows)["region_verdicts"]
    return out


def format_options(res: dict) -> str:
    """A before/after table: one line per setting."""
    head = (
        f"{'setting':>15} {'low-contrast parts':>20} {'ring overlaps':>14} {'min dB A/P':>10} "
        f"{'max P SL':>8} {'max onset P SL':>14} {'max gap s':>9}  hand verdicts"
    )
    out = [head]
    for name in ("paper", "ringdown_gap", "contrast_floor", "both"):
        pp = res[name]["pair_problems"]
        out.append(
            f"{name:>15} {len(pp['low_contrast']):>20} {len(pp['ringdown_overlap']):>14} "
            f"{pp['min_contrast_db']:10.1f} {pp['max_passive_sl_db']:8.1f} "
            f"{pp['max_onset_passive_sl_db']:14.1f} {pp['max_gap_s']:9.3f}  "
            f"{res[name].get('region_verdicts', '')}"
        )
    return "\n".join(out)


def run_bench(ctx, quick: bool) -> dict:
    """``haptable bench closed-loop``: predicted vs achieved for the default pairs (all
    parts) and regions (four directions); both table rules compared (``rules``:
    ``rule_check.compare_rules``, all pairs and the pairs under the default regions in
    steady state, the default pairs played, and the accelerance-derived map); without
    ``--quick`` also every hand region at 60 mm steps, four directions (left/down play the parts of right/up in the other
    order: same tones, different ring-down overlap)."""
    from console.bench import machine_info
    from console.kernel.client import open_outputs

    profile, pm = ctx.profile, ctx.pm
    t0 = time.perf_counter()
    with _one_blas_thread():
        vmap = measured_map(profile, pm)
    t_map = time.perf_counter() - t0
    flow, hand = effects_of(profile, pm)
    t0 = time.perf_counter()
    tables = flow.tables(vmap=vmap, rule="paper")  # the paper's rule (Fig. 8)
    t_tab = time.perf_counter() - t0
    ls = LoopSettings()
    regions = DEFAULT_REGIONS[:2] if quick else DEFAULT_REGIONS
    res: dict = {"machine": machine_info(), "part_s": ls.part_s}
    with open_outputs(profile, pm, fast=True) as out:
        t0 = time.perf_counter()
        pairs = flow_pairs_check(out, profile, tables, DEFAULT_PAIRS, ls, plugins=pm)
        t_pairs = time.perf_counter() - t0
        t0 = time.perf_counter()
        hands = hand_regions_check(out, profile, vmap, regions, ls=ls, plugins=pm)
        t_hands = time.perf_counter() - t0
        if not quick:
            centers = hand.region_centers(60.0, vmap=vmap)
            t0 = time.perf_counter()
            scan = hand_regions_check(out, profile, vmap, centers, ls=ls, plugins=pm)
            res["scan"] = {
                "regions": len(centers),
                "step_mm": 60.0,
                "directions": ["left", "right", "up", "down"],
                "s": time.perf_counter() - t0,
                **summarize([], scan),
                "problems": [
                    f"{r['region']} {r['direction']} part {r['part']}: {verdict(r)}"
                    for r in scan
                    if verdict(r) != "ok"
                ],
            }
        t0 = time.perf_counter()
        opts = compare_options(
            out,
            profile,
            vmap,
            DEFAULT_PAIRS,
            OPTION_REGIONS[:1] if quick else OPTION_REGIONS,
            ("right", "left") if quick else ("left", "right", "up", "down"),
            plugins=pm,
        )
        res["options"] = {
            "s": time.perf_counter() - t0,
            "min_contrast_db": opts["min_contrast_db"],
            "ringdown_gap_k": opts["ringdown_gap_k"],
            "table": format_options(opts).splitlines(),
            **{
                name: {
                    "pair_problems": opts[name]["pair_problems"],
                    "region_verdicts": opts[name].get("region_verdicts"),
                    "pairs_table": format_pairs(opts[name]["pairs"]).splitlines(),
                }
                for name in ("paper", "ringdown_gap", "contrast_floor", "both")
            },
        }
        from .rule_check import compare_rules, format_rules, without_rows

        t0 = time.perf_counter()
        rules = compare_rules(
            out,
            profile,
            vmap,
            plugins=pm,
            played_pairs=DEFAULT_PAIRS[:3] if quick else DEFAULT_PAIRS,
            regions=DEFAULT_REGIONS,
        )
        res["rules"] = {
            "s": time.perf_counter() - t0,
            "table": format_rules(rules).splitlines(),
            **without_rows(rules),
        }
    res.update(
        {
            "map_measure_s": t_map,
            "tables_build_s": t_tab,
            "pairs_s": t_pairs,
            "regions_s": t_hands,
            "summary": summarize(pairs, hands),
            "pairs_table": format_pairs(pairs).splitlines(),
            "regions_table": format_regions(hands).splitlines(),
            "pairs": pairs,
            "regions": hands,
        }
    )
    return res
