"""``haptable frf``, ``tables``, ``flow`` and ``point`` commands."""

from __future__ import annotations

import argparse
import json
import sys
import time
from pathlib import Path

import numpy as np

from console.errors import UserError
from console.options import finite_float, from_field


def _key(name: str, unit: str = ""):
    """The option type of one overriding ``[vibrotactile] name``: the key's range."""
    from plugins.vibrotactile import field

    return from_field(field("vibrotactile", name), unit=unit)


# ---------------------------------------------------------------------- helpers
def progress_printer(min_s: float = 1.0):
    """A progress callback for the CLI: prints to stderr once the work passed ``min_s``."""
    t0 = time.perf_counter()
    state = {"shown": False}

    def cb(frac: float, msg: str) -> None:
        if time.perf_counter() - t0 < min_s and frac < 1.0:
            return
        if frac >= 1.0 and not state["shown"]:
            return
        state["shown"] = True
        bar = "#" * int(frac * 30)
        end = "\n" if frac >= 1.0 else ""
        print(f"\r{msg} [{bar:<30}] {frac * 100:3.0f}%", end=end, file=sys.stderr, flush=True)

    return cb


def _vt(ctx) -> dict:
    return ctx.profile.section("vibrotactile")


def settings_of(ctx):
    """Stimulus settings from the profile (the registered effects read the same)."""
    from plugins.vibrotactile.effects import setup_from_profile

    return setup_from_profile(ctx.profile).settings


def piezo_limits(ctx) -> dict:
    """The piezo range the safety gate allows (profile limits and amplifier/card reach)."""
    from console.safety import Limits

    lo, hi = Limits.from_profile(ctx.profile).piezo_range()
    return {
        "piezo_min_v": lo,
        "piezo_max_v": hi,
        "max_plan_s": float(ctx.profile.get("limits.max_plan_s")),
    }


def perception_of(ctx):
    from plugins.vibrotactile.perception import Perception

    return Perception.from_section(ctx.profile.section("perception"))


def cache_dir_of(args, ctx) -> Path | None:
    from plugins.vibrotactile.cache import default_cache_dir

    raw = getattr(args, "cache_dir", None) or _vt(ctx)["cache_dir"]
    if raw == "none":
        return None
    return Path(raw).expanduser() if raw else default_cache_dir()


#: an amplifier gain (generator volts -> piezo volts; PI E413.D2: 50)
GAIN = finite_float(1e-6, 1e6, note="the amplifier's gain, e.g. 50")

#: the map argument naming the profile's measured map (HapTable's one cache)
MEASURED = "measured"
MAP_HELP = (
    "a vibration map (.npz), or 'measured': the profile's measured map, the file the "
    "console's Vibration screen and the flow demo use (measured first when there is none)"
)


def map_source(source: str, ctx) -> str:
    """``source``, or for ``measured`` (when no file has that name) the profile's measured
    map in HapTable's cache (``console.runtime.measured_map``), measured with the profile's
    vibrometer first when the cache has none."""
    if source != MEASURED or Path(source).exists():
        return source
    from console.runtime.measured_map import measured_map_file

    return str(measured_map_file(ctx.profile, ctx.pm, progress_printer()))


def sample_rate(ctx) -> float:
    return float(ctx.profile.get("audio.sample_rate_hz"))


def finite(name: str, value: float | None, lo: float, hi: float, fix: str) -> float | None:
    """A number argument within [lo, hi] (``None`` passes): else one line naming it."""
    if value is not None and not lo <= value <= hi:  # NaN fails too
        raise UserError(f"{name} {value:g}: {fix}")
    return value


def parse_point(text: str, vmap):
    """``51`` (point id: the map's node number) -> map index; ``x,y`` (mm) -> (x, y), finite."""
    t = text.strip()
    hint = "give a point id of the map (its node number) or x,y in mm (e.g. 300,200)"
    if "," in t:
        try:
            x, y = (float(v) for v in t.split(","))
        except ValueError:
            raise UserError(f"point {text!r}: {hint}") from None
        if not (np.isfinite(x) and np.isfinite(y)):
            raise UserError(f"point {text!r}: x and y must be finite numbers in mm; {hint}")
        return (x, y)
    try:
        num = int(t)
    except ValueError:
        raise UserError(f"point {text!r}: {hint}") from None
    return vmap.point_index(num)


def tables_for(path: str, ctx, args, band_hz: float | None = None):
    """Tables from a tables file, or built (and cached) from a vibration map."""
    from console.vibration_map import load_map
    from plugins.vibrotactile.lazy import tables_cached
    from plugins.vibrotactile.tables import load_tables
    from plugins.vibrotactile.vibration_io import is_tables_file

    path = map_source(path, ctx)
    if is_tables_file(path):
        t = load_tables(path, sample_rate_hz=sample_rate(ctx))
        want = getattr(args, "rule", None)
        if want is not None and want != t.rule:
            raise UserError(
                f"{path}: tables built with the {t.rule} rule, not {want}; rebuild them with "
                f"`haptable tables build MAP --out FILE --rule {want}` or give the map"
            )
        return t
    vm = load_map(
        path,
        require_all=not getattr(args, "allow_missing", False),
    )
    c, per = table_rule_of(ctx, args)
    return tables_cached(
        vm,
        band_hz or _vt(ctx)["band_hz"],
        cache_dir_of(args, ctx),
        progress_printer(),
        min_contrast_db=c,
        perceptual=per,
    )


def table_rule_of(ctx, args):
    """(min_contrast_db, PerceptualRule or None) from ``--rule``/``--min-contrast-db`` and
    the profile's ``[vibrotactile] table_rule`` and ``min_contrast_db``."""
    from plugins.vibrotactile.perceptual import rule_from_profile

    c = getattr(args, "min_contrast_db", None)
    rule = getattr(args, "rule", None)
    if rule is None:  # as the effects' Setup.rule_of: a contrast floor is the paper's rule
        floor = c is not None or float(_vt(ctx).get("min_contrast_db", 0.0)) > 0
        rule = "paper" if floor else str(_vt(ctx).get("table_rule", "perceptual"))
    if rule == "paper":
        c = float(_vt(ctx).get("min_contrast_db", 0.0)) if c is None else float(c)
        return c, None
    if c:
        raise UserError(
            f"--min-contrast-db {c:g} applies to --rule paper only; the perceptual rule "
            "weighs contrast itself"
        )
    return 0.0, rule_from_profile(ctx.profile, sample_rate(ctx))


def emit_plan(plan, args, ctx, summary: dict) -> int:
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


# ---------------------------------------------------------------------- frf
def configure_frf(p: argparse.ArgumentParser) -> None:
    sub = p.add_subparsers(dest="frf_cmd", metavar="ACTION", required=True)
    i = sub.add_parser(
        "import",
        help="UFF 58/58b -> vibration map: EXC=FILE per excitation, or one FILE for all",
    )
    i.add_argument(
        "files",
        nargs="+",
        metavar="EXC=FILE|FILE",
        help="PA=pa.uff PB=pb.uff ... PALL=all.uff, or one file holding every excitation "
        "(told apart by reference node: --ref-node)",
    )
    i.add_argument("--out", required=True, help="vibration map (.npz) to write")
    i.add_argument(
        "--ref-node",
        nargs="+",
        metavar="EXC=NODE",
        default=None,
        help="one file for all: the reference node of each excitation (default PA=1 PB=2 "
        "PC=3 PD=4 PALL=5)",
    )
    i.add_argument(
        "--gain",
        type=GAIN,
        default=None,
        help="amplifier gain: the UFF reference is generator volts (default: the gain a "
        "HapTable export stored, else profile amplifiers.piezo_gain)",
    )
    i.add_argument(
        "--mask-below-hz",
        type=_key("mask_below_hz", "Hz"),
        default=None,
        help="mask bins below (default: a HapTable export's mask, else profile)",
    )
    i.add_argument(
        "--reference",
        choices=("voltage", "force"),
        default="voltage",
        help="what the FRF is per: generator voltage (default) or a measured force (m/N: "
        "needs --sensitivity-n-per-v)",
    )
    i.add_argument(
        "--sensitivity-n-per-v",
        type=finite_float(1e-9, 1e9, unit="N/V"),
        default=None,
        help="with --reference force: newtons of that force per generator volt",
    )
    i.add_argument(
        "--allow-missing", action="store_true", help="accept fewer than five excitations"
    )
    e = sub.add_parser(
        "export", help="vibration map -> UFF 58, one file per excitation (or --one-file)"
    )
    e.add_argument("map", help=MAP_HELP)
    e.add_argument("--out", required=True, help="folder for PA.uff ... PALL.uff")
    e.add_argument("--binary", action="store_true", help="write binary 58b")
    e.add_argument(
        "--one-file",
        action="store_true",
        help="write DIR/all.uff holding every excitation (ref_node PA=1 .. PALL=5)",
    )
    e.add_argument(
        "--gain",
        type=GAIN,
        default=1.0,
        help="amplifier gain: write per generator volt = map x gain (1: per piezo volt); "
        "stored in the files, so import reads it back",
    )
    m = sub.add_parser(
        "measure",
        help="measure the profile's vibration map with its vibrometer (twin: simulated) into "
        "HapTable's cache, where the console and the demos read it ('measured' as a MAP)",
    )
    m.add_argument("--out", default=None, help="also write the map (.npz) here")
    s = sub.add_parser("info", help="summarise a vibration map")
    s.add_argument("map", help=MAP_HELP)
    s.add_argument("--json", action="store_true")


def run_frf(args, ctx) -> int:
    if args.frf_cmd == "import":
        from console.vibration_map import grid_points_mm, save_map
        from plugins.vibrotactile.uff_io import import_uff

        plain = [f for f in args.files if "=" not in f]
        if plain and (len(args.files) > 1):
            raise UserError(
                f"{plain[0]!r}: give EXC=FILE per excitation (PA=pa.uff ...) or one FILE for "
                "all excitations (with --ref-node), not both"
            )
        if plain:
            files = plain[0]
        else:
            if args.ref_node:
                raise UserError("--ref-node: only for one FILE holding every excitation")
            files = {}
            for item in args.files:
                exc, path = item.split("=", 1)
                files[exc.strip().upper()] = path
        ref_nodes = None
        if args.ref_node:
            ref_nodes = {}
            for item in args.ref_node:
                exc, _, num = item.partition("=")
                try:
                    ref_nodes[exc.strip().upper()] = int(num)
                except ValueError:
                    raise UserError(f"--ref-node {item!r}: write EXC=NODE, e.g. PA=1") from None
        g = ctx.profile.section("grid")
        grid = grid_points_mm(g["rows"], g["columns"], g["pitch_mm"], tuple(g["origin_mm"]))
        m = import_uff(
            files,
            gain=args.gain,
            mask_below_hz=args.mask_below_hz,
            grid_mm=grid,
            require_all=not args.allow_missing,
            ref_nodes=ref_nodes,
            reference=args.reference,
            sensitivity_n_per_v=args.sensitivity_n_per_v,
            default_gain=ctx.profile.get("amplifiers.piezo_gain"),
            default_mask_below_hz=_vt(ctx)["mask_below_hz"],
        )
        gain = m.provenance["gain"]
        save_map(args.out, m)
        print(
            f"wrote {args.out}: {len(m.excitations)} excitations x {m.points.size} points x "
            f"{m.freq_hz.size} bins ({m.freq_hz[0]:g}-{m.freq_hz[-1]:g} Hz), gain {gain:g}"
            + (f"; note: {m.provenance['note']}" if m.provenance.get("note") else "")
        )
        return 0
    if args.frf_cmd == "measure":
        return measure_map(args, ctx)
    from console.vibration_map import load_map

    if args.frf_cmd == "export":
        from plugins.vibrotactile.uff_io import export_uff

        m = load_map(map_source(args.map, ctx), require_all=False)
        for path in export_uff(
            m, args.out, binary=args.binary, gain=args.gain, one_file=args.one_file
        ):
            print(f"wrote {path}")
        return 0
    m = load_map(map_source(args.map, ctx), require_all=False)
    info = {
        "excitations": list(m.excitations),
        "points": int(m.points.size),
        "bins": int(m.freq_hz.size),
        "freq_hz": [float(m.freq_hz[0]), float(m.freq_hz[-1])],
        "masked_bins": int(m.masked.sum()),
        "peak_um_per_v": float(np.abs(m.frf_um_per_v).max()),
        "provenance": m.provenance,
    }
    if args.json:
        print(json.dumps(info, indent=2))
    else:
        from plugins.vibrotactile.summary_text import summary_lines

        print("\n".join(summary_lines(info)))
    return 0


def measure_map(args, ctx) -> int:
    """Measure the grid with the vibrometer the profile names into HapTable's cache (the
    file the console and the demos read: ``console.runtime.measured_map``), and copy it
    to ``--out`` when given."""
    from console.runtime.measured_map import measured_map_file
    from console.vibration_map import load_map, save_map

    cached = measured_map_file(ctx.profile, ctx.pm, progress_printer(), remeasure=True)
    m = load_map(cached)
    wrote = [str(cached)]
    if args.out:
        out = Path(args.out)
        if out.suffix.lower() != ".npz":
            raise UserError(f"--out {out}: give a .npz path for the vibration map")
        out.parent.mkdir(parents=True, exist_ok=True)
        save_map(out, m)
        wrote.insert(0, str(out))
    name = ctx.profile.get("vibrometer.driver") or "the only vibrometer"
    print(
        f"wrote {' and '.join(wrote)}: {len(m.excitations)} excitations x {m.points.size} "
        f"points x {m.freq_hz.size} bins ({m.freq_hz[0]:g}-{m.freq_hz[-1]:g} Hz) from "
        f"vibrometer {name!r}"
    )
    return 0


# ---------------------------------------------------------------------- tables
def add_rule_option(p: argparse.ArgumentParser) -> None:
    p.add_argument(
        "--rule",
        choices=("perceptual", "paper"),
        default=None,
        help="table rule. perceptual: the entry the finger tells apart best (felt "
        "active-minus-passive difference in JND above the [perception] threshold, at the "
        "drive the amplifier can deliver, inside [vibrotactile] play_band_hz); paper: "
        "largest displacement difference (Fig. 8). Default: profile [vibrotactile] "
        "table_rule (perceptual); a tables file keeps the rule it was built with",
    )


def configure_tables(p: argparse.ArgumentParser) -> None:
    sub = p.add_subparsers(dest="tables_cmd", metavar="ACTION", required=True)
    b = sub.add_parser("build", help="vibration map -> lookup tables (paper Fig. 8)")
    b.add_argument("map", help=MAP_HELP)
    b.add_argument("--out", required=True)
    b.add_argument(
        "--band-hz",
        type=_key("band_hz", "Hz"),
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
        type=_key("min_contrast_db", "dB"),
        default=None,
        help="contrast-aware ranking: an entry needs active/passive >= this many dB (largest "
        "difference among those; best contrast where none reaches it). Default: profile "
        "[vibrotactile] min_contrast_db, 0 = the paper's rule (largest absolute difference)",
    )
    add_rule_option(b)
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
    from plugins.vibrotactile.tables import build_tables, query_indices, query_points, save_tables

    if args.tables_cmd == "build":
        from console.vibration_map import load_map

        nyq = sample_rate(ctx) / 2
        finite("--band-hz", args.band_hz, 1e-3, nyq, f"give a band in Hz up to Nyquist ({nyq:g})")
        c, per = table_rule_of(ctx, args)
        m = load_map(map_source(args.map, ctx), require_all=not args.allow_missing)
        t0 = time.perf_counter()
        t = build_tables(
            m,
            args.band_hz or _vt(ctx)["band_hz"],
            progress_printer(),
            min_contrast_db=c,
            perceptual=per,
        )
        dt = time.perf_counter() - t0
        save_tables(args.out, t)
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
            method=args.method or _vt(ctx)["interpolation"],
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


# ---------------------------------------------------------------------- flow / point
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
        type=_key("hand_mm", "mm"),
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
        type=_key("min_contrast_db", "dB"),
        default=None,
        help="from a map: the paper's tables with this contrast floor (default: profile; "
        "0 = the paper's rule without floor)",
    )
    add_rule_option(p)
    p.add_argument(
        "--ringdown-k",
        type=_key("ringdown_gap_k"),
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

    from plugins.vibrotactile.effects import HandFlowEffect, setup_from_profile
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
