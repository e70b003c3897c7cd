"""``haptable signals``: the signal library from the command line.

haptable signals list
haptable signals show NAME|'EXPR'
haptable signals play NAME|'EXPR' [--patch PA[,PC] | --screen] [--dry-run] [--fast]
    (a library signal meant for a channel plays there; another is refused)
haptable signals add NAME 'EXPR' [--description TEXT] [--target PA|screen] [--replace]
haptable signals rm NAME
haptable signals import FILE.ahap|FILE.haptic [--name N] [--level 40 V]
haptable signals export NAME --format ahap|haptic -o FILE
"""

from __future__ import annotations

import argparse
import json
import sys
from pathlib import Path

from console.cli import haptic_commands
from console.cli.commands import play_and_report
from console.config.profile import _printable
from console.config.signal_library import (
    add_signal,
    get_signal,
    library_data,
    library_path,
    read_library,
    remove_signal,
)
from console.core.errors import UserError
from console.safety import Limits
from console.signals.design import Target, parse_target, render, summarize
from console.signals.expr import parse


def configure(p: argparse.ArgumentParser) -> None:
    p.epilog = (
        "Expressions: e.g. 'seq(sine(250 Hz, 40 V, 0.5 s) * adsr(10 ms, 50 ms, 0.7, 100 ms), "
        "silence(0.2 s)) * 3'; a unit after every value; volts at the actuator."
    )
    sub = p.add_subparsers(dest="action", metavar="ACTION", required=True)
    ls = sub.add_parser("list", help="the library's signals (built-in ones marked)")
    ls.add_argument("--json", action="store_true")
    show = sub.add_parser("show", help="duration, peak, RMS and dominant frequency")
    show.add_argument("signal", help="a library name or an expression")
    show.add_argument("--json", action="store_true")
    play = sub.add_parser("play", help="play through the safety gate on patches or the screen")
    play.add_argument("signal", help="a library name or an expression")
    where = play.add_mutually_exclusive_group()
    where.add_argument(
        "--patch", help="PA, PA,PC, PALL ... (default: the channel the signal is meant for)"
    )
    where.add_argument("--screen", action="store_true", help="the electrovibration screen")
    play.add_argument("--dry-run", action="store_true", help="check it, do not play it")
    play.add_argument("--fast", action="store_true", help="twin: fast-forward")
    play.add_argument("--out", help="also write the plan as a 2-channel WAV")
    add = sub.add_parser("add", help="save an expression under a name")
    add.add_argument("name")
    add.add_argument("expr")
    add.add_argument("--description", default="")
    add.add_argument(
        "--target", default="", help="the channel it is meant for: PA, PA,PC, PALL or screen"
    )
    add.add_argument("--replace", action="store_true", help="replace a signal of that name")
    rm = sub.add_parser("rm", help="remove a saved signal")
    rm.add_argument("name")
    haptic_commands.configure(sub)


def _list(path: Path, as_json: bool) -> int:
    """The library; an entry that does not validate is one line on stderr (exit 2), the
    others are listed all the same."""
    lib = read_library(path)
    problems = list(lib.problems.values())
    if as_json:
        rows = [
            {
                "name": e.name,
                "expr": e.expr,
                "description": e.description,
                "builtin": e.builtin,
                "target": e.target,
            }
            for e in lib.entries.values()
        ]
        print(json.dumps({"file": str(path), "signals": rows, "problems": problems}, indent=2))
    else:
        print(f"library: {path}" + ("" if path.exists() else " (none saved yet)"))
        width = max(len(n) for n in lib.entries)
        for e in lib.entries.values():
            tag = (f" [on {e.target}]" if e.target else "") + (" [built-in]" if e.builtin else "")
            print(f"  {e.name:<{width}}  {e.expr}{tag}")
            if e.description:
                print(f"  {'':<{width}}  {e.description}")
    for line in problems:
        print(f"haptable: error: {line}", file=sys.stderr)
    return 2 if problems else 0


def _resolve(ctx, text: str) -> tuple[str, str]:
    """(name, expression) for a library name or an expression typed in place."""
    path = library_path(ctx.profile.name)
    if "(" in text:
        return "expression", text
    return text, get_signal(path, text).expr


def _play_target(args, ctx, name: str) -> Target:
    """Where ``signals play`` plays: the channel a library signal is meant for (its
    ``target``), refused when ``--patch`` or ``--screen`` names another; an expression
    or a signal meant for none needs one of them."""
    given = "screen" if args.screen else args.patch
    entry = None if name == "expression" else get_signal(library_path(ctx.profile.name), name)
    meant = entry.target if entry is not None else ""
    if not given and not meant:
        raise UserError(f"{name}: give where it plays, --patch PA (PA,PC, PALL) or --screen")
    target = parse_target(given or meant)
    if meant and target != parse_target(meant):
        flag = "--screen" if meant == "screen" else f"--patch {meant}"
        raise UserError(
            f"{name} is meant for {meant}, not {target.label}: play it with {flag} (or "
            "leave both out), or save a copy with --target for the other channel"
        )
    return target


def run(args, ctx) -> int:
    path = library_path(ctx.profile.name)
    action = args.action
    if action == "list":
        return _list(path, args.json)
    if action == "add":
        limits = Limits.from_profile(ctx.profile)
        e = add_signal(
            path,
            args.name,
            args.expr,
            args.description,
            replace=args.replace,
            limits=limits,
            target=args.target,
        )
        print(f"saved {e.name} in {path}")
        return 0
    if action == "rm":
        remove_signal(path, args.name)
        # lazy: the breakpoint data of an imported signal goes with it
        from console.signals.breakpoint_data import remove

        data = " and its breakpoint data" if remove(path, args.name) else ""
        print(f"removed {_printable(args.name)}{data} from {path}")
        return 0
    if action == "import":
        return haptic_commands.run_import(args, ctx, path)
    name, expr = _resolve(ctx, args.signal)
    node = parse(expr, data=library_data(path))  # @NAME: breakpoint data beside the library
    if action == "export":
        return haptic_commands.run_export(args, ctx, name, node)
    if action == "show":
        fs = int(ctx.profile.get("audio.sample_rate_hz"))
        x = render(node, fs, max_s=float(ctx.profile.get("limits.max_plan_s")), what=name)
        s = summarize(x, fs)
        if args.json:
            print(json.dumps({"name": name, "expr": expr, **s.__dict__}))
        else:
            print(f"{name}: {expr}")
            print(f"  duration {s.duration_s:.3f} s")
            print(f"  peak     {s.peak_v:.2f} V")
            print(f"  RMS      {s.rms_v:.2f} V")
            print(f"  dominant {s.dominant_hz:.1f} Hz")
        return 0
    if action == "play":
        # lazy: keeps `haptable` startup light
        from console.session.audition import audition_plan

        target = _play_target(args, ctx, name)
        plan = audition_plan(ctx.profile, node, target, name)
        return play_and_report(ctx, plan, fast=args.fast, out=args.out, dry_run=args.dry_run)
    raise UserError(f"unknown action {action!r}")  # pragma: no cover - argparse refuses it
