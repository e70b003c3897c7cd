"""Console start-up benchmark: process start to the first painted frame.

Phases (from process start): ``main`` the interpreter is up, ``plugins`` the plugin
manager is loaded (every built-in plugin imported), ``profile`` the profile is validated,
``textual`` the console's modules are imported; then the first paint.

``run(ctx, quick)`` starts ``python -m console.benchmarks.console_startup --child PROFILE`` several times;
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
    times: dict[str, float] = {"main": time.monotonic()}
    # lazy: the child times these imports
    from console.config.plugins import load_plugins
    from console.runtime.context import Context

    plugins = load_plugins()
    times["plugins"] = time.monotonic()
    ctx = Context(profile, plugins)
    _ = ctx.profile
    times["profile"] = time.monotonic()
    # lazy: the child times Textual's import
    from console.tui.app import HapTableApp

    times["textual"] = time.monotonic()
    app = HapTableApp(ctx, fast=True)

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
        [sys.executable, "-m", "console.benchmarks.console_startup", "--child", profile or ""],
        capture_output=True,
        text=True,
        env=env,
        timeout=60,
        check=True,
    )
    line = [ln for ln in out.stdout.splitlines() if ln.startswith("{")][-1]
    t = json.loads(line)
    return {f"{k}_s": v - t0 for k, v in t.items()}


def run(ctx, quick: bool) -> dict:
    """``haptable bench console``: start-up to first paint (target < 1 s)."""
    # lazy: bench_stats brings NumPy; this module loads none
    from console.core.bench_stats import machine_info, summarize_s

    n = 3 if quick else 10
    prof = ctx.profile_arg
    runs = [startup_once(prof) for _ in range(n)]
    return {
        "first_paint": summarize_s([r["paint_s"] for r in runs]),
        "phases_from_process_start": {
            phase: summarize_s([r[f"{phase}_s"] for r in runs])
            for phase in ("main", "plugins", "profile", "textual")
        },
        "runs": n,
        "target_ms": 1000,
        "machine": machine_info(),
    }


if __name__ == "__main__":
    if len(sys.argv) >= 2 and sys.argv[1] == "--child":
        _child(sys.argv[2] or None if len(sys.argv) > 2 else None)
    else:
        print(json.dumps(run(None, quick="--quick" in sys.argv), indent=2, default=float))
