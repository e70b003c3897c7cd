"""Closed-loop check: flows rendered from a measured map, played through the safety gate,
and the plate twin's true response to what was played, against what the tables predicted.

Used by ``tests/closed_loop`` and the ``closed-loop`` benchmark (``loop_bench``). The stimuli come from the
effects offering ``FlowPatchDrives`` and ``HandFlowGeometry`` (``loop_play.effects_of``,
asked by capability: this is a consumer of their plans, exactly as a scene is); the outputs are the profile's (twin
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
from typing import TYPE_CHECKING

import numpy as np

from console.plugin_api import UserError

from .closed_loop import hand_subgrid_mm, square_levels_um, twin_of
from .loop_play import (
    DEFAULT_PAIRS,
    DEFAULT_REGIONS,
    LoopSettings,
    effects_of,
    one_blas_thread,
    play_and_envelope,
)
from .loop_report import pair_problems, summarize

if TYPE_CHECKING:
    from console.plugin_api import Plugins


def flow_pairs_check(
    outputs,
    profile,
    tables,
    pairs=DEFAULT_PAIRS,
    ls: LoopSettings | None = None,
    *,
    plugins: Plugins,
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
    with one_blas_thread():
        return _flow_pairs_check(
            outputs, profile, tables, pairs, ls, plugins, min_contrast_db, ringdown_gap_k
        )


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
        env = play_and_envelope(outputs, profile, twin, plan, pts, ls, 2, freqs)
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
    plugins: Plugins,
    ringdown_gap_k: float | None = None,
) -> list[dict]:
    """One row per (region, direction, part): square levels predicted from the map vs
    achieved on the twin, against the 3-JND line; a flow the map cannot make is a row
    with ``ok`` False and its reason. ``screen_stride`` as in ``haptable flow --hand``
    (3: staged search; 1: exhaustive). ``ringdown_gap_k``: the effect's ring-down gap
    (default the profile's). Regions are rendered at their centre rounded to 0.1 mm."""
    with one_blas_thread():
        return _hand_regions_check(
            outputs, profile, vmap, regions, directions, ls, screen_stride, plugins, ringdown_gap_k
        )


def _hand_regions_check(
    outputs, profile, vmap, regions, directions, ls, screen_stride, plugins, ringdown_gap_k
):

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
            env = play_and_envelope(outputs, profile, twin, plan, pts, ls, 0, freqs)
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


#: The options ``compare_options`` turns on (suggested values, not the defaults): a
#: 10 dB contrast floor keeps the passive point 10 dB below the active one (first-mode
#: entries at ~2 dB never win); 3 decay times of silence put part 1's ring 26 dB down.
OPTION_CONTRAST_DB = 10.0
OPTION_RINGDOWN_K = 3.0
#: Hand regions for the comparison: where the whole-table scan (60 mm steps) found part 1
#: ringing into part 2 above the 3-JND line, and the right edge (low headroom).
OPTION_REGIONS: tuple[tuple[float, float], ...] = ((281.73, 223.645), (641.73, 163.645))


def compare_options(
    outputs,
    profile,
    vmap,
    pairs=DEFAULT_PAIRS,
    regions=DEFAULT_REGIONS,
    directions=("left", "right", "up", "down"),
    *,
    plugins: Plugins,
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
