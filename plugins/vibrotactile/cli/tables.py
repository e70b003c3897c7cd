"""``haptable tables``: build lookup tables from a map, query a pair."""

from __future__ import annotations

import argparse
import json
import sys
import time

from console.plugin_api import UserError, finite_float, load_map
from plugins.vibrotactile.cli.common import (
    MAP_HELP,
    add_rule_option,
    key_type,
    map_source,
    parse_point,
    progress_printer,
    sample_rate,
    table_rule_of,
    tables_for,
    vt_section,
)


def finite(name: str, value: float | None, lo: float, hi: float, fix: str) -> float | None:
    """A number argument within [lo, hi] (``None`` passes): else one line naming it."""
    if value is not None and not lo <= value <= hi:  # NaN fails too
        raise UserError(f"{name} {value:g}: {fix}")
    return value


def configure_tables(p: argparse.ArgumentParser) -> None:
    sub = p.add_subparsers(dest="tables_cmd", metavar="ACTION", required=True)
    b = sub.add_parser("build", help="vibration map -> lookup tables (paper Fig. 8)")
    b.add_argument("map", help=MAP_HELP)
    b.add_argument("--out", required=True)
    b.add_argument(
        "--band-hz",
        type=key_type("band_hz", "Hz"),
        default=None,
        help="usable band (default: profile, 650 Hz)",
    )
    b.add_argument(
        "--allow-missing", action="store_true", help="build from the excitations present"
    )
    b.add_argument(
        "--zeta",
        type=finite_float(0, 1, above=True),
        default=0.01,
        help="damping assumed by the resolution check",
    )
    b.add_argument(
        "--min-contrast-db",
        type=key_type("min_contrast_db", "dB"),
        default=None,
        help="contrast-aware ranking: an entry needs active/passive >= this many dB (largest "
        "difference among those; best contrast where none reaches it). Default: profile "
        "[vibrotactile] min_contrast_db, 0 = the paper's rule (largest absolute difference)",
    )
    add_rule_option(b)
    b.add_argument(
        "--thresholds",
        default=None,
        metavar="FILE",
        help="a person's thresholds.json (DIR/P01/thresholds.json): the perceptual rule "
        "scores at their vibrotactile threshold instead of the [perception] curve",
    )
    q = sub.add_parser("query", help="max difference, frequency and actuator for (active, passive)")
    q.add_argument(
        "tables",
        help="tables file, or a vibration map (tables built and cached); 'measured': the "
        "profile's measured map",
    )
    q.add_argument("--active", required=True, help="point id (the map's node number) or x,y in mm")
    q.add_argument("--passive", required=True, help="point id (node number) or x,y in mm")
    q.add_argument(
        "--method",
        choices=("spline", "keys", "bilinear", "modal"),
        default=None,
        help="off-grid interpolation (modal: fitted modes, a fit of ~10 s per map, cached)",
    )
    q.add_argument("--extrapolate", action="store_true", help="allow points outside the grid")
    add_rule_option(q)
    q.add_argument("--cache-dir", default=None)
    q.add_argument("--json", action="store_true")


def run_tables(args, ctx) -> int:
    # lazy: this module loads at every haptable start; tables only when used
    from plugins.vibrotactile.tables import build_tables, query_indices, query_points, save_tables

    if args.tables_cmd == "build":
        nyq = sample_rate(ctx) / 2
        finite("--band-hz", args.band_hz, 1e-3, nyq, f"give a band in Hz up to Nyquist ({nyq:g})")
        c, per = table_rule_of(ctx, args)
        m = load_map(map_source(args.map, ctx), require_all=not args.allow_missing)
        band = args.band_hz or vt_section(ctx)["band_hz"]
        if args.thresholds:  # a person's threshold curve (person_thresholds.py)
            # lazy: loaded when this runs, not when the module is imported
            from plugins.vibrotactile.person_thresholds import personal_rule
            from plugins.vibrotactile.tables import rule_bins

            if per is None:
                raise UserError("--thresholds applies to the perceptual rule: drop --rule paper")
            per = personal_rule(per, args.thresholds, m.freq_hz[rule_bins(m, band, per, c)])
        t0 = time.perf_counter()
        t = build_tables(
            m,
            band,
            progress_printer(),
            min_contrast_db=c,
            perceptual=per,
        )
        dt = time.perf_counter() - t0
        save_tables(args.out, t)
        # lazy: this module loads at every haptable start; tables only when used
        from plugins.vibrotactile.tables import coarse_peaks

        missed = coarse_peaks(m, args.zeta, t.band_hz)
        if missed:
            worst = max(missed, key=lambda d: d["worst_loss_pct"])
            print(
                f"warning: {len(missed)} resonance peaks are narrower than the bin spacing (zeta "
                f"{args.zeta:g}); e.g. {worst['excitation']} at {worst['frequency_hz']:g} Hz may lose up "
                f"to {worst['worst_loss_pct']:.0f} % (df {worst['df_hz']:g} Hz > bandwidth "
                f"{worst['half_power_bw_hz']:.2f} Hz): measure with finer lines",
                file=sys.stderr,
            )
        rule = f", rule {t.rule}" + (f", contrast >= {c:g} dB" if c > 0 else "")
        rule += f", thresholds of {args.thresholds}" if args.thresholds else ""
        print(
            f"wrote {args.out}: {m.points.size} x {m.points.size} pairs x {len(m.excitations)} "
            f"excitations up to {t.band_hz:g} Hz{rule} in {dt * 1e3:.0f} ms"
        )
        return 0
    t = tables_for(args.tables, ctx, args)
    a, b = parse_point(args.active, t.vmap), parse_point(args.passive, t.vmap)
    if isinstance(a, int) and isinstance(b, int):
        ans = query_indices(t, a, b)
    else:
        xy = [t.vmap.points_mm[p] if isinstance(p, int) else p for p in (a, b)]
        ans = query_points(
            t,
            tuple(xy[0]),
            tuple(xy[1]),
            method=args.method or vt_section(ctx)["interpolation"],
            extrapolate=args.extrapolate,
        )
    ans["rule"] = t.rule
    if args.json:
        print(json.dumps(ans))
    elif ans["actuator"] is None:
        print(ans["note"])
    else:
        felt = ""
        if "felt_jnd" in ans:
            felt = (
                f", felt difference {ans['felt_db']:.1f} dB = {ans['felt_jnd']:.1f} JND "
                f"(contrast {ans['contrast_db']:.1f} dB)"
            )
        print(
            f"{ans['max_difference_um_per_v']:.4g} um/V at {ans['frequency_hz']:g} Hz with "
            f"{ans['actuator']} (rule {t.rule}{felt})"
        )
    return 0
