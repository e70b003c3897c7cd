"""The ``core`` plugin as the CLI registers it: the core's profile sections, the core
commands and the console's own benchmarks.

It sits at the top layer (it names the commands and the benchmarks), so the plugin manager
never imports it: ``console.cli.main`` passes it to ``load_plugins(core=...)``.
"""

from __future__ import annotations

from console.config.core_sections import haptable_profile_sections
from console.core.hookspecs import hookimpl

__all__ = [
    "haptable_profile_sections",
    "haptable_register_benchmarks",
    "haptable_register_commands",
]


@hookimpl
def haptable_register_commands(register):
    # lazy: SciPy loads only when a command is registered
    from console.cli import commands, signal_commands

    commands.register_core(register)
    register(
        "signals",
        signal_commands.configure,
        signal_commands.run,
        help="the signal library: list, show, play on patches or the screen, add, rm",
    )


@hookimpl
def haptable_register_benchmarks(register):
    def console_startup(ctx, quick: bool) -> dict:
        # lazy: a benchmark loads only when it runs
        from console.benchmarks.console_startup import run

        return run(ctx, quick)

    register("console", console_startup, help="console start-up to first paint (target < 1 s)")

    def console_demo(ctx, quick: bool, minutes: float | None = None) -> dict:
        # lazy: a benchmark loads only when it runs
        from console.benchmarks.console_demo import run

        return run(ctx, quick, minutes=minutes)

    def safety(ctx, quick: bool) -> dict:
        # lazy: a benchmark loads only when it runs
        from console.benchmarks.safety import run

        return run(ctx, quick)

    register(
        "safety",
        safety,
        help="what a client can send the table's kernel (random faulty plans, stream "
        "parameters, relay commands, malformed messages: cases per second, problems found, "
        "on a private twin), `haptable estop` from a shell, and e-stop -> silence of a "
        "running demo beside the console",
    )

    def gate_fill(ctx, quick: bool) -> dict:
        # lazy: a benchmark loads only when it runs
        from console.benchmarks.gate_fill import run

        return run(ctx, quick)

    register(
        "gate-fill",
        gate_fill,
        help="the safety gate's work per audio block (the callback's fill): p50/p99 while "
        "idle, playing and ramping down after an e-stop",
    )

    def signals(ctx, quick: bool) -> dict:
        # lazy: a benchmark loads only when it runs
        from console.benchmarks.signals import run

        return run(ctx, quick)

    register(
        "signals",
        signals,
        help="signal designer: parse, render and gate-check time per expression, and the "
        "renderers' error against analytic references (frequency, chirp, ADSR levels)",
    )

    def haptic_files(ctx, quick: bool) -> dict:
        # lazy: a benchmark loads only when it runs
        from console.benchmarks.haptic_files import run

        return run(ctx, quick)

    register(
        "haptic-files",
        haptic_files,
        help="AHAP and .haptic import/export time, the imported envelope against the "
        "file's breakpoints and the export -> import round trip (fraction of full scale)",
    )

    register(
        "console-demo",
        console_demo,
        help="demos started from the console for --minutes (5): the knob's loop latency "
        "per screen, its crossing -> detent at the driver, underruns (by cause, audible), "
        "the operator's finger moved on the flow demo (key -> flow scheduled), output log",
    )

    def console_idle(ctx, quick: bool) -> dict:
        # lazy: a benchmark loads only when it runs
        from console.benchmarks.console_idle import run

        return run(ctx, quick)

    register(
        "console-idle",
        console_idle,
        help="the console's CPU while idle, per screen (haptable in tmux 120x40, each "
        "screen 10 s from /proc/<pid>/stat, % of one core; goal <= 3 %, Camera <= 20 %)",
    )

    def demo_cancel(ctx, quick: bool) -> dict:
        # lazy: a benchmark loads only when it runs
        from console.benchmarks.demo_cancel import run

        return run(ctx, quick)

    register(
        "demo-cancel",
        demo_cancel,
        help="the flow demo's start cancelled at points of its start (its process "
        "starting, its preparation): cancel -> its process ended (p50/p99), starts that "
        "came up first, processes left running, the outputs after",
    )

    def tracking(ctx, quick: bool) -> dict:
        # lazy: a benchmark loads only when it runs
        from console.benchmarks.tracking import run

        return run(ctx, quick)

    register(
        "tracking",
        tracking,
        help="hand and contact identities on the twin: tracker time per frame (p50/p99), "
        "blob sessions of a resting hand per 10 s, centre step against the palm's (mm)",
    )
