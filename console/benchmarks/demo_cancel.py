"""``haptable bench demo-cancel``: how long a demo's start takes to end after a cancel
(the Scenes screen's ``x``), by where in its start the cancel comes.

The flow demo is started as the console starts it (``DemoProcess`` on the profile's
table, the console's camera lent), and cancelled at each point of ``POINTS``: while its
interpreter starts, just after it begins preparing (camera, classifier, the flow's
effects and planner), and later in that preparation. Reported per point and overall:
cancel -> its process ended (p50/p99/max ms), how many starts came up before the cancel
took (then it is a stop), the processes it had started still running 2 s after it
ended, and the table's outputs after every trial (silent, relays open, not e-stopped).
"""

from __future__ import annotations

import time
from pathlib import Path
from typing import Any

from console.core.bench_stats import machine_info, summarize_s
from console.runtime.demo_process import DemoCancelled, DemoProcess

#: (the start's step to wait for, seconds after it): where a cancel comes
POINTS = (
    ("starting its process", 0.3),
    ("opening the camera", 0.2),
    ("opening the camera", 1.5),
)


def descendants(pid: int) -> set[int]:
    """The processes below ``pid`` now (Linux ``/proc``; elsewhere none)."""
    parent: dict[int, int] = {}
    for d in Path("/proc").glob("[0-9]*"):
        try:
            parent[int(d.name)] = int((d / "stat").read_text().rsplit(")", 1)[1].split()[1])
        except (OSError, ValueError, IndexError):
            continue
    out, todo = set(), [pid]
    while todo:
        below = todo.pop()
        kids = [c for c, p in parent.items() if p == below]
        out.update(kids)
        todo += kids
    return out


def _alive(pid: int) -> bool:
    try:
        state = Path(f"/proc/{pid}/stat").read_text().rsplit(")", 1)[1].split()[0]
    except (OSError, IndexError):
        return False
    return state != "Z"


def one_cancel(ctx: Any, out: Any, step: str, after_s: float) -> dict:
    """Start the flow demo, cancel it ``after_s`` after its start says ``step``."""
    seen: dict[str, float] = {}
    kids: set[int] = set()

    def progress(frac: float, text: str) -> None:
        if step in text:
            seen.setdefault("step", time.monotonic())

    def cancelled() -> bool:
        kids.update(descendants(run.proc.pid))  # what it started so far
        t = seen.get("step")
        if t is None or time.monotonic() < t + after_s:
            return False
        seen.setdefault("cancel", time.monotonic())
        return True

    run = DemoProcess(ctx.profile, "flow", plugins=ctx.pm, table_dir=out.table.dir, fast=out.fast)
    try:
        run.wait_started(progress, cancelled, timeout_s=300.0)
        seen.setdefault("cancel", time.monotonic())  # it came up first: it is stopped
        run.stop("cancelled")
    except DemoCancelled:
        pass
    took_s = time.monotonic() - seen["cancel"]
    came_up = run.scene_name is not None  # its preparation ended, the demo ran
    time.sleep(2.0)
    st = out.status()
    return {
        "took_s": took_s,
        "came_up": came_up,
        "exit_code": run.proc.poll(),
        "left_running": sum(_alive(p) for p in kids),
        "outputs_ok": not st["busy"]
        and not st["gate"]["relays_closed"]
        and not any(st["gate"]["level_v"])
        and not out.estopped,
    }


def run(ctx: Any, quick: bool) -> dict:
    rounds = 1 if quick else 5
    by_point: dict[str, list[dict]] = {}
    with ctx.outputs(fast=False) as out:
        for _ in range(rounds):
            for step, after_s in POINTS:
                got = one_cancel(ctx, out, step, after_s)
                by_point.setdefault(f"{step} + {after_s:g} s", []).append(got)
    trials = [t for ts in by_point.values() for t in ts]
    return {
        "cancel_to_ended_ms": summarize_s([t["took_s"] for t in trials]),
        "by_point": {
            k: {
                "cancel_to_ended_ms": summarize_s([t["took_s"] for t in ts]),
                "came_up": sum(t["came_up"] for t in ts),
                "exit_codes": sorted({t["exit_code"] for t in ts}, key=str),
            }
            for k, ts in by_point.items()
        },
        "trials": len(trials),
        "came_up_before_the_cancel": sum(t["came_up"] for t in trials),
        "left_running": sum(t["left_running"] for t in trials),
        "outputs_silent_open_after_each": all(t["outputs_ok"] for t in trials),
        "machine": machine_info(),
    }
