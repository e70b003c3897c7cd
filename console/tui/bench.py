"""Console start-up benchmark: process start to the first painted frame.

``run(ctx, quick)`` starts ``python -m console.tui.bench --child PROFILE`` several times;
each child builds the console exactly as ``haptable`` does (plugins, profile, app) and,
headless, reports the ``time.monotonic()`` of its first refresh after mount (the first
paint) and exits. The parent measured the process start on the same clock.
"""

from __future__ import annotations

import json
import os
import subprocess
import sys
import time


def _child(profile: str | None) -> None:
    t_main = time.monotonic()
    from console.cli import Context
    from console.plugins import load_plugins
    from console.tui.app import HapTableApp

    ctx = Context(profile, load_plugins())
    _ = ctx.profile
    app = HapTableApp(ctx, fast=True)
    times: dict[str, float] = {"main": t_main}

    def painted() -> None:
        times["paint"] = time.monotonic()
        app.exit()

    app.call_after_refresh(lambda: app.call_after_refresh(painted))
    app.run(headless=True, size=(80, 24))
    print(json.dumps(times))


def startup_once(profile: str | None = None) -> dict[str, float]:
    """One cold start: seconds from process start to Python main and to the first paint."""
    env = dict(os.environ)
    t0 = time.monotonic()
    out = subprocess.run(
        [sys.executable, "-m", "console.tui.bench", "--child", profile or ""],
        capture_output=True,
        text=True,
        env=env,
        timeout=60,
        check=True,
    )
    line = [ln for ln in out.stdout.splitlines() if ln.startswith("{")][-1]
    t = json.loads(line)
    return {"interpreter_s": t["main"] - t0, "first_paint_s": t["paint"] - t0}


def run(ctx, quick: bool) -> dict:
    """``haptable bench console``: start-up to first paint (target < 1 s)."""
    from console.bench import machine_info, summarize_s

    n = 3 if quick else 10
    prof = getattr(ctx, "profile_arg", None)
    runs = [startup_once(prof) for _ in range(n)]
    return {
        "first_paint": summarize_s([r["first_paint_s"] for r in runs]),
        "interpreter": summarize_s([r["interpreter_s"] for r in runs]),
        "runs": n,
        "target_ms": 1000,
        "machine": machine_info(),
    }


if __name__ == "__main__":
    if len(sys.argv) >= 2 and sys.argv[1] == "--child":
        _child(sys.argv[2] or None if len(sys.argv) > 2 else None)
    else:
        print(json.dumps(run(None, quick="--quick" in sys.argv), indent=2, default=float))
