"""``haptable bench closed-loop``: the closed-loop checks on the default pairs and
regions, the options and the two table rules compared, with their times."""

from __future__ import annotations

import time

from console.plugin_api import machine_info
from console.plugin_api.runtime import open_outputs

from .loop_check import (
    OPTION_REGIONS,
    compare_options,
    flow_pairs_check,
    hand_regions_check,
)
from .loop_play import (
    DEFAULT_PAIRS,
    DEFAULT_REGIONS,
    LoopSettings,
    effects_of,
    measured_map,
    one_blas_thread,
)
from .loop_report import format_options, format_pairs, format_regions, summarize, verdict
from .rule_check import compare_rules, format_rules, without_rows


def run_bench(ctx, quick: bool) -> dict:
    """``haptable bench closed-loop``: predicted vs achieved for the default pairs (all
    parts) and regions (four directions); both table rules compared (``rules``:
    ``rule_check.compare_rules``, all pairs and the pairs under the default regions in
    steady state, the default pairs played, and the accelerance-derived map); without
    ``--quick`` also every hand region at 60 mm steps, four directions (left/down play the parts of right/up in the other
    order: same tones, different ring-down overlap)."""
    profile, pm = ctx.profile, ctx.pm
    t0 = time.perf_counter()
    with one_blas_thread():
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
