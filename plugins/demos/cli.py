"""``haptable demo flow|knob``: run a demo end to end and show the loop's latency."""

from __future__ import annotations

import argparse
import json
import os
import sys
import time
from dataclasses import replace
from pathlib import Path

from console.plugin_api import UserError, integer, minutes, seconds

#: the knob's sectors ([knob] sectors, the electrostatic plugin's key: same range)
SECTORS = integer(2, 64, note="the paper's: 8, 16, 32")


def configure(p: argparse.ArgumentParser) -> None:
    p.add_argument(
        "demo", choices=("flow", "knob", "soak"), help="which demo (soak: the benchmark)"
    )
    p.add_argument("--condition", default=None, help="knob condition (default: [demos])")
    p.add_argument("--sectors", type=SECTORS, default=None, help="knob sectors (default: [knob])")
    p.add_argument(
        "--direction", choices=("left", "right", "up", "down"), default=None, help="flow direction"
    )
    p.add_argument(
        "--seconds",
        type=seconds(zero="until Ctrl-C"),
        default=10.0,
        help="run this long (0: until Ctrl-C)",
    )
    p.add_argument("--minutes", type=minutes(), default=None, help="soak: run this long")
    p.add_argument("--no-script", action="store_true", help="twin: no scripted hand")
    p.add_argument(
        "--tuio",
        action="store_true",
        help="also stream TUIO ([tuio] version 1.1 or 2.0, host/port)",
    )
    p.add_argument("--json", action="store_true", help="print the final snapshot as JSON")
    p.add_argument("--record", metavar="FILE", default=None, help="record the run (HDF5)")


def _ms(x: float) -> str:
    return "-" if x != x else f"{x:.1f}"


def _line(snap: dict) -> str:
    lat = snap["latency"]
    e2e = lat["end_to_end"]
    extra = ""
    if "knob" in snap:
        k = snap["knob"]
        item = f"item {k['item']:>3}" if int(k["item"]) >= 0 else "no item "
        extra = f"{item}  angle {k['angle_deg']:7.1f} deg  crossings {k['crossings']}"
    elif "flow" in snap:
        extra = f"flows {snap['flow']['flows']} ({snap['flow']['direction']})"
    return (
        f"{snap['uptime_s']:6.1f} s  {lat['fps']:5.1f} fps  frame->output p50 "
        f"{_ms(e2e['p50_ms'])} p99 {_ms(e2e['p99_ms'])} ms  cpu/frame p99 "
        f"{_ms(lat['cpu_per_frame']['p99_ms'])} ms  dropped {lat['dropped_queue']}"
        f"+{lat['dropped_camera']}  {extra}"
    )


def _progress(done: int, total: int, what: str) -> None:
    print(f"preparing {done + 1}/{total}: {what}", file=sys.stderr, flush=True)


def _recording_to(ctx, path: str):
    """The profile with ``[recording]`` on and writing to ``path`` (the sink ``recording``)."""
    if "recording" not in ctx.pm.of("frame_sink"):
        raise UserError("--record: no plugin registers the frame sink 'recording'; unblock it")
    target = Path(path).expanduser().resolve()
    if not target.parent.is_dir():  # said before the camera and the outputs start
        raise UserError(
            f"--record {target}: folder {target.parent} does not exist; create it or give "
            "another path"
        )
    rec = {**ctx.profile.section("recording"), "enabled": True, "path": str(target)}
    return replace(ctx.profile, data={**ctx.profile.data, "recording": rec})


def run(args, ctx) -> int:
    if args.demo == "soak":
        # lazy: this module loads at every haptable start; bench only when used
        from .bench import run_soak

        out = run_soak(ctx, False, minutes=args.minutes if args.minutes is not None else 10.0)
        print(json.dumps(out, indent=2, default=float) if args.json else out)
        return 0
    start = ctx.pm.get("demo", args.demo).factory  # the registered demo (this plugin's)
    profile = ctx.profile if args.record is None else _recording_to(ctx, args.record)
    who = f"the {args.demo} demo (haptable demo {args.demo}, pid {os.getpid()})"
    with ctx.outputs(fast=False, who=who) as out:  # the console plays nothing meanwhile
        run_ = start(
            profile,
            ctx.pm,
            out,
            script=not args.no_script,
            condition=args.condition,
            sectors=args.sectors,
            direction=args.direction,
            tuio=True if args.tuio else None,
            progress=None if args.json else _progress,
            # a recording replays the same only from a prepared demo (its plans all ready)
            prepare_first=args.record is not None,
        )
        t0 = time.monotonic()
        try:
            while not args.seconds or time.monotonic() - t0 < args.seconds:
                time.sleep(1.0)
                snap = run_.snapshot()
                if not args.json:
                    print(_line(snap), file=sys.stderr, flush=True)
                if snap["watchdog"]["tripped"]:
                    raise UserError(snap["watchdog"]["reason"])
        except KeyboardInterrupt:
            pass
        finally:
            run_.stop()
        snap = run_.snapshot()
        snap["outputs"] = {"audio": out.status()["audio"], "gate": out.status()["gate"]}
    if args.json:
        print(json.dumps(snap, indent=2, default=str))
    else:
        print(_line(snap))
    return 0
