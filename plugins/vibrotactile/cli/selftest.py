"""``haptable selftest [--json] [--quick]``: every relay path chirped and compared with the
baseline (``plugins.vibrotactile.selftest``); each finding one line with its fix, exit 1
on a fault. ``doctor_part(ctx)`` is the quick part ``haptable doctor`` runs."""

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
    p.add_argument("--doctor", action="store_true", help=argparse.SUPPRESS)  # doctor's part


def skipped_why(profile: Any) -> str | None:
    """Why no self-test can run on this profile (no sensor among the inputs), or None."""
    if profile.get("audio.driver") == "twin":
        return None  # the twin's sensor is always there
    if find_input(input_specs(profile), "accelerometer") is None:
        return (
            "no accelerometer among [audio_inputs]: add [audio_inputs.accel] channel = 1, "
            "kind = 'accelerometer', sensitivity = 10.2 and glue it at [selftest] "
            "reference_point"
        )
    return None


def selftest_report(ctx: Any, *, quick: bool, baseline=None, save=False, fast=None) -> dict:
    # lazy: numpy, the outputs client and the test load only when run
    from console.plugin_api.runtime import open_outputs
    from plugins.vibrotactile.selftest import reference_point, run_selftest

    reference_point(ctx.profile)  # a bad point is one line before anything plays
    with open_outputs(ctx.profile, ctx.pm, fast=fast) as out:
        return run_selftest(out, ctx.profile, quick=quick, baseline=baseline, save=save)


def run_selftest_cmd(args, ctx) -> int:
    if args.doctor:
        d = doctor_part(ctx)
        if args.json:
            print(json.dumps(d))
        else:
            for line in d["lines"]:
                print(f"  {'selftest':<10} {'quick':<12} {d['state']:<9} {line}")
        return 1 if d["state"] == "error" else 0
    why = skipped_why(ctx.profile)
    if why:
        raise UserError(f"{ctx.profile.path}: selftest: {why}")
    fast = True if args.fast else None
    r = selftest_report(
        ctx, quick=args.quick, baseline=args.baseline, save=args.save_baseline, fast=fast
    )
    if args.json:
        print(json.dumps(r, indent=1))
    else:
        for line in r["lines"]:
            print(line)
        print(
            f"({len(r['paths'])} paths at grid point {r['reference_point']}, {r['elapsed_s']:.1f} s)"
        )
    return 0 if r["ok"] else 1


def doctor_part(ctx: Any) -> dict:
    """The quick self-test for ``haptable doctor``: state ok | error | skipped, the lines."""
    why = skipped_why(ctx.profile)
    if why:
        return {"state": "skipped", "lines": [f"skipped: {why}"]}
    # lazy: the test's module loads only when run
    from plugins.vibrotactile.selftest import baseline_path

    if not baseline_path(ctx.profile).exists():
        why = "no baseline yet: run `haptable selftest` on a healthy table to keep one"
        return {"state": "skipped", "lines": [f"skipped: {why}"]}
    twin = ctx.profile.get("audio.driver") == "twin"
    try:
        r = selftest_report(ctx, quick=True, fast=True if twin else None)
    except UserError as e:
        return {"state": "error", "lines": [str(e)]}
    return {"state": "ok" if r["ok"] else "error", "lines": r["lines"]}
