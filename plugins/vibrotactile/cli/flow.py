"""``haptable flow`` (between two points or under a hand) and ``haptable point``: a plan
written as .wav + .json, played through the safety gate, or summarised."""

from __future__ import annotations

import argparse
import json
from pathlib import Path

import numpy as np

from console.plugin_api import UserError
from plugins.vibrotactile.cli.common import (
    add_rule_option,
    cache_dir_of,
    key_type,
    map_source,
    parse_point,
    perception_of,
    piezo_limits,
    sample_rate,
    settings_of,
    tables_for,
)
from plugins.vibrotactile.settings import setup_from_profile


def emit_plan(plan, args, ctx, summary: dict) -> int:
    # lazy: this module loads at every haptable start; stimuli only when used
    from plugins.vibrotactile.stimuli import plan_to_wav

    if args.out:
        out = Path(args.out)
        out.parent.mkdir(parents=True, exist_ok=True)
        if out.suffix.lower() != ".wav":
            raise UserError(
                f"--out {out}: give a .wav path (the plan summary goes beside it as .json)"
            )
        fs = ctx.profile.get("amplifiers.piezo_gain") * ctx.profile.get("audio.full_scale_v")
        guard = (
            2 * ctx.profile.get("relays.guard_ms") + ctx.profile.get("relays.switch_time_ms")
        ) / 1e3
        plan_to_wav(plan, out, volts_full_scale=fs, guard_s=guard)
        out.with_suffix(".json").write_text(json.dumps(summary, indent=2, default=float))
        summary["wav"] = str(out)
    if getattr(args, "play", False):
        with ctx.outputs() as o:
            o.play(plan)
        summary["played"] = True
    if args.json:
        print(json.dumps(summary, indent=2, default=float))
    else:
        # lazy: this module loads at every haptable start; summary_text only when used
        from plugins.vibrotactile.summary_text import summary_lines

        print("\n".join(summary_lines(summary)))
    return 0


def plan_summary(plan) -> dict:
    return {
        "name": plan.name,
        "duration_s": plan.duration_s,
        "segments": [
            {
                "label": s.label,
                "patches": sorted(s.patches),
                "peak_v": float(np.abs(s.piezo_v).max()),
            }
            for s in plan.segments
        ],
        **{k: v for k, v in plan.meta.items()},
    }


def configure_flow(p: argparse.ArgumentParser) -> None:
    p.add_argument(
        "source",
        metavar="TABLES|MAP",
        help="tables file, or a vibration map; 'measured': the profile's measured map",
    )
    p.add_argument("--from", dest="from_", help="start point: point id (node number) or x,y mm")
    p.add_argument("--to", help="end point: point id (node number) or x,y mm")
    p.add_argument("--hand", help="hand centre x,y in mm (flow under a hand)")
    p.add_argument(
        "--direction", choices=("left", "right", "up", "down"), help="flow direction under the hand"
    )
    p.add_argument(
        "--hand-mm",
        type=key_type("hand_mm", "mm"),
        default=None,
        help="hand area side (default: profile, 120 mm)",
    )
    p.add_argument(
        "--exhaustive",
        action="store_true",
        help="hand: score every bin on the full subgrid (slower; default: staged search)",
    )
    p.add_argument(
        "--min-contrast-db",
        type=key_type("min_contrast_db", "dB"),
        default=None,
        help="from a map: the paper's tables with this contrast floor (default: profile; "
        "0 = the paper's rule without floor)",
    )
    add_rule_option(p)
    p.add_argument(
        "--ringdown-k",
        type=key_type("ringdown_gap_k"),
        default=None,
        help="silence between the parts >= k decay times of part 1's mode (default: "
        "profile [vibrotactile] ringdown_gap_k; 0 = relay gap only)",
    )
    p.add_argument("--out", help="write the plan as a .wav (sound-card units) + .json summary")
    p.add_argument("--play", action="store_true", help="play through the safety gate")
    p.add_argument("--cache-dir", default=None, help="cache folder ('none' to disable)")
    p.add_argument("--json", action="store_true")


def with_ringdown(st, args):
    """Settings with ``--ringdown-k`` applied."""
    from dataclasses import replace

    k = getattr(args, "ringdown_k", None)
    if k is None:
        return st
    return replace(st, ringdown_gap_k=float(k))


def run_flow(args, ctx) -> int:
    # lazy: this module loads at every haptable start; stimuli only when used
    from plugins.vibrotactile.stimuli import flow_plan

    lim = piezo_limits(ctx)
    if args.hand:
        if not args.direction:
            raise UserError("--hand needs --direction left|right|up|down")
        plan, summary = hand_plan(args, ctx, lim)
        return emit_plan(plan, args, ctx, summary)
    if not (args.from_ and args.to):
        raise UserError("give --from P --to Q (point ids or x,y mm), or --hand X,Y --direction D")
    t = tables_for(args.source, ctx, args)
    a, b = parse_point(args.from_, t.vmap), parse_point(args.to, t.vmap)
    plan = flow_plan(
        t,
        a,
        b,
        perception_of(ctx),
        with_ringdown(settings_of(ctx), args),
        name=f"flow {args.from_}->{args.to}",
        **lim,
    )
    return emit_plan(plan, args, ctx, plan_summary(plan))


def hand_plan(args, ctx, lim):
    """The flow under a hand through the ``hand_flow`` effect (same plan as a scene's)."""
    from dataclasses import replace

    # lazy: this module loads at every haptable start; hand_flow_effect, tables only when used
    from plugins.vibrotactile.hand_flow_effect import HandFlowEffect
    from plugins.vibrotactile.tables import load_map_or_tables

    vm = load_map_or_tables(
        map_source(args.source, ctx),
        require_all=False,
        sample_rate_hz=sample_rate(ctx),
    )
    try:
        cx, cy = (float(v) for v in args.hand.split(","))
    except ValueError:
        raise UserError(f"--hand {args.hand!r}: give the hand centre as x,y in mm") from None
    if not (np.isfinite(cx) and np.isfinite(cy)):
        raise UserError(f"--hand {args.hand!r}: x and y must be finite numbers in mm")
    setup = replace(
        setup_from_profile(ctx.profile),
        cache_dir=cache_dir_of(args, ctx),
        piezo_min_v=lim["piezo_min_v"],
        piezo_max_v=lim["piezo_max_v"],
    )
    k = getattr(args, "ringdown_k", None)
    plan = HandFlowEffect(ctx.profile, setup).render(
        (cx, cy),
        args.direction,
        vmap=vm,
        hand_mm=args.hand_mm,
        exhaustive=args.exhaustive,
        ringdown_gap_k=k,
    )
    summary = plan_summary(plan)
    for p in summary.get("parts", []):
        p.pop("x_um", None)
    return plan, summary


def configure_point(p: argparse.ArgumentParser) -> None:
    p.add_argument(
        "source",
        metavar="TABLES|MAP",
        help="tables file, or a vibration map; 'measured': the profile's measured map",
    )
    p.add_argument("point", help="point id (node number) or x,y in mm")
    p.add_argument("--out", help="write the plan as a .wav + .json summary")
    p.add_argument("--play", action="store_true")
    p.add_argument("--cache-dir", default=None)
    p.add_argument("--json", action="store_true")


def run_point(args, ctx) -> int:
    # lazy: this module loads at every haptable start; stimuli only when used
    from plugins.vibrotactile.stimuli import point_plan

    t = tables_for(args.source, ctx, args)
    a = parse_point(args.point, t.vmap)
    plan = point_plan(
        t,
        a,
        perception_of(ctx),
        settings_of(ctx),
        name=f"point {args.point}",
        **piezo_limits(ctx),
    )
    return emit_plan(plan, args, ctx, plan_summary(plan))
