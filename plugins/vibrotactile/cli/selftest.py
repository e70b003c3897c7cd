"""``haptable selftest [--json] [--quick]``: every relay path chirped and compared with the
baseline, or the stored vibration map on a table without one (``--against-map``: always;
``plugins.vibrotactile.selftest``, ``selftest_map``); ``--sensor amp_monitor``: the
amplifiers' monitors instead of the accelerometer (``selftest_monitor``). Each finding
one line with its fix, exit 1 on a fault. ``doctor_part(ctx)`` is the quick part
``haptable doctor`` runs (``--doctor --estimate``: whether it would skip and why, nothing
played: the console's Devices row says it as doctor would)."""

from __future__ import annotations

import argparse
import json
from typing import Any

from console.plugin_api import Field, UserError, find_input, input_specs

SELFTEST_FIELDS = {
    "reference_point": Field(
        "int",
        52,
        min=1,
        help="grid point where the self-test's sensor sits (off the table's symmetry lines, "
        "so that PA/PC and PB/PD differ there)",
    ),
    "baseline": Field(
        "path",
        "",
        must_exist=False,
        help="the self-test baseline file (default: the data dir's selftest/PROFILE-baseline.npz)",
    ),
    "map": Field(
        "path",
        "",
        must_exist=False,
        help="the vibration map a table without a baseline is tested against (default: the "
        "profile's measured map)",
    ),
}


def configure_selftest(p: argparse.ArgumentParser) -> None:
    p.add_argument("--json", action="store_true")
    p.add_argument("--quick", action="store_true", help="one chirp per patch, no PALL")
    p.add_argument("--baseline", default=None, help="the baseline file (see [selftest])")
    p.add_argument(
        "--save-baseline",
        action="store_true",
        help="measure and keep this run as the baseline (a healthy table, after a repair)",
    )
    p.add_argument("--fast", action="store_true", help="twin: fast-forward, not real time")
    p.add_argument(
        "--against-map",
        action="store_true",
        help="compare with the stored vibration map at the reference point even when a "
        "baseline is kept (a table without one always is)",
    )
    p.add_argument("--map", default=None, help="that vibration map file (see [selftest] map)")
    p.add_argument(
        "--sensor",
        choices=("accelerometer", "amp_monitor"),
        default=None,
        help="what measures: the accelerometer at the reference point, or the amplifiers' "
        "monitor inputs (channel gains only; default: the accelerometer when there is one)",
    )
    p.add_argument("--doctor", action="store_true", help=argparse.SUPPRESS)  # doctor's part
    p.add_argument(
        "--estimate",
        action="store_true",
        help="say how long the run plays (seconds of chirps, paths) and play nothing",
    )


def skipped_why(profile: Any) -> str | None:
    """Why no self-test can run on this profile (no sensor among the inputs), or None."""
    if profile.get("audio.driver") == "twin":
        return None  # the twin's sensor is always there
    specs = input_specs(profile)
    if find_input(specs, "accelerometer") is None and find_input(specs, "amp_monitor") is None:
        return (
            "no accelerometer among [audio_inputs]: add [audio_inputs.accel] channel = 1, "
            "kind = 'accelerometer', sensitivity = 10.2 (mV per m/s^2: a 100 mV/g sensor) "
            "and glue it at [selftest] "
            "reference_point (or an amp_monitor input for the amplifiers alone)"
        )
    return None


def sensor_of(profile: Any, asked: str | None) -> str:
    """The sensor a run uses: the one asked for, else the accelerometer when there is one
    (the twin's always), else the amplifiers' monitors."""
    if asked:
        return asked
    twin = profile.get("audio.driver") == "twin"
    if twin or find_input(input_specs(profile), "accelerometer") is not None:
        return "accelerometer"
    return "amp_monitor"


def stored_map(ctx: Any, given: str | None) -> Any:
    """The map a table is tested against: ``--map``, ``[selftest] map``, the profile's
    kept measured map, else (the twin) its measured map; None when there is none."""
    # lazy: the map's loader and the runtime load only when a map is wanted
    from pathlib import Path

    from console.plugin_api import load_map
    from console.plugin_api.runtime import kept_measured_map, measured_map

    p = given or ctx.profile.get("selftest.map")
    if p:
        if not Path(p).is_file():
            raise UserError(
                f"{p}: no such vibration map; give the map the table's effects use (see "
                "`haptable frf`) with --map or [selftest] map"
            )
        return load_map(Path(p))
    vmap = kept_measured_map(ctx.profile)
    if vmap is None and ctx.profile.get("audio.driver") == "twin":
        vmap = measured_map(ctx.profile, ctx.pm)  # the twin's: measured once, then kept
    return vmap


def selftest_report(
    ctx: Any,
    *,
    quick: bool,
    baseline=None,
    save=False,
    fast=None,
    against_map: bool = False,
    map_file: str | None = None,
    sensor: str | None = None,
) -> dict:
    # lazy: numpy, the outputs client and the test load only when run
    from console.plugin_api.runtime import open_outputs
    from plugins.vibrotactile.selftest import baseline_path, reference_point, run_selftest

    if sensor_of(ctx.profile, sensor) == "amp_monitor":
        from plugins.vibrotactile.selftest_monitor import run_monitor_selftest  # lazy: as above

        with open_outputs(ctx.profile, ctx.pm, fast=fast) as out:
            return run_monitor_selftest(out, ctx.profile, input_specs(ctx.profile))
    reference_point(ctx.profile)  # a bad point is one line before anything plays
    vmap = None
    if not save and (against_map or map_file or not baseline_path(ctx.profile, baseline).exists()):
        vmap = stored_map(ctx, map_file)
    with open_outputs(ctx.profile, ctx.pm, fast=fast) as out:
        return run_selftest(
            out,
            ctx.profile,
            quick=quick,
            baseline=baseline,
            save=save,
            vmap=vmap,
            against="map" if against_map else "auto",
        )


def run_selftest_cmd(args, ctx) -> int:
    if args.doctor:
        d = doctor_part(ctx, play=not args.estimate)
        if args.json:
            print(json.dumps(d))
        else:
            for line in d["lines"]:
                print(f"  {'selftest':<10} {'quick':<12} {d['state']:<9} {line}")
        return 1 if d["state"] == "error" else 0
    why = skipped_why(ctx.profile)
    if why:
        raise UserError(f"{ctx.profile.path}: selftest: {why}")
    if args.estimate:
        return _estimate(args, ctx)
    fast = True if args.fast else None
    with ctx.holding_table():  # its chirps are measured: the console's plays would be too
        r = selftest_report(
            ctx,
            quick=args.quick,
            baseline=args.baseline,
            save=args.save_baseline,
            fast=fast,
            against_map=args.against_map,
            map_file=args.map,
            sensor=args.sensor,
        )
    if args.json:
        print(json.dumps(r, indent=1))
    else:
        for line in r["lines"]:
            print(line)
        if r.get("sensor") == "amp_monitor":
            print(
                f"({len(r['paths'])} amplifier channels on their monitors, {r['elapsed_s']:.1f} s)"
            )
        else:
            print(
                f"({len(r['paths'])} paths at grid point {r['reference_point']}"
                + (f" against the {r['against']}" if r.get("against") else "")
                + f", {r['elapsed_s']:.1f} s)"
            )
    return 0 if r["ok"] else 1


def _estimate(args, ctx) -> int:
    """``--estimate``: the seconds of audio a run plays and its paths, nothing played."""
    # lazy: the test's module loads only when asked
    from plugins.vibrotactile.selftest import planned_s

    if sensor_of(ctx.profile, args.sensor) == "amp_monitor":
        raise UserError("selftest --estimate: the amplifiers' monitor test has no estimate yet")
    seconds, paths = planned_s(ctx.profile, quick=args.quick)
    first = _map_first(ctx, args)
    if args.json:
        print(json.dumps({"planned_s": seconds, "paths": paths, "map_first": first}))
    else:
        then = "; the twin's vibration map is measured first" if first else ""
        print(f"{paths} paths, {seconds:.1f} s of chirps and ring-out{then}")
    return 0


def _map_first(ctx, args) -> bool:
    """Whether a run measures the twin's vibration map before its chirps (no baseline,
    no map given or kept: the first run on a fresh twin)."""
    # lazy: as in _estimate
    from console.plugin_api.runtime import kept_measured_map
    from plugins.vibrotactile.selftest import baseline_path

    if ctx.profile.get("audio.driver") != "twin" or args.save_baseline:
        return False
    if args.map or ctx.profile.get("selftest.map"):
        return False
    if baseline_path(ctx.profile, args.baseline).exists() and not args.against_map:
        return False
    return kept_measured_map(ctx.profile) is None


def doctor_skipped(profile: Any) -> str | None:
    """Why ``haptable doctor``'s quick part skips on ``profile`` (no sensor, no baseline
    yet), or None: it would run."""
    why = skipped_why(profile)
    if why:
        return why
    # lazy: the test's module loads only when asked
    from plugins.vibrotactile.selftest import baseline_path

    monitor = sensor_of(profile, None) == "amp_monitor"  # it needs no baseline
    if not monitor and not baseline_path(profile).exists():
        return "no baseline yet: run `haptable selftest` on a healthy table to keep one"
    return None


def doctor_part(ctx: Any, play: bool = True) -> dict:
    """The quick self-test for ``haptable doctor``: state ok | error | skipped, the lines;
    ``play`` False (``--doctor --estimate``: the console's Devices row): nothing plays,
    state skipped with why, else ``not run`` (it would run)."""
    why = doctor_skipped(ctx.profile)
    if why:
        return {"state": "skipped", "lines": [f"skipped: {why}"]}
    if not play:
        return {"state": "not run", "lines": []}
    twin = ctx.profile.get("audio.driver") == "twin"
    try:
        r = selftest_report(ctx, quick=True, fast=True if twin else None)
    except UserError as e:
        return {"state": "error", "lines": [str(e)]}
    return {"state": "ok" if r["ok"] else "error", "lines": r["lines"]}
