"""The closed-loop checks' rows read for people: a verdict per hand-flow part, tables
of pairs, regions and options, and the headline numbers."""

from __future__ import annotations

import numpy as np


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
