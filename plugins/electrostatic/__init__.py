"""Electrostatic friction and the haptic knob (paper 4.2, 5.3-5.5).

Registers: effects ``electrostatic`` (one friction stimulus with its expected force) and
``knob`` (the four conditions and variants, finite or live); profile sections
[electrostatic] and [knob]; the ``haptable knob`` command; the ``knob`` benchmark.
Modules: force (Eqs. 1-2, thresholds), rotation (two-finger tracker), knob (sectors),
synth (live stream), session/simulate (pipeline and twin), task (the experiment).
"""

from __future__ import annotations

from typing import Any

from console.hookspecs import hookimpl


@hookimpl
def haptable_profile_sections(register: Any) -> None:
    from .settings import ELECTROSTATIC_FIELDS, KNOB_FIELDS

    register(
        "electrostatic",
        ELECTROSTATIC_FIELDS,
        help="electrovibration model (paper Eqs. 1-2) and detection thresholds",
    )
    register("knob", KNOB_FIELDS, help="haptic knob: sectors, feedback signals, tracker, task")


@hookimpl
def haptable_register_effects(register: Any) -> None:
    def electrostatic(profile: Any) -> Any:
        from .effects import ElectrostaticEffect

        return ElectrostaticEffect(profile)

    def knob(profile: Any) -> Any:
        from .effects import KnobEffect

        return KnobEffect(profile)

    register(
        "electrostatic",
        electrostatic,
        description="one electrovibration stimulus on the screen, with its expected force",
    )
    register(
        "knob",
        knob,
        description="haptic knob conditions V, HD, HD+CF, HD+VF and variants (live stream)",
    )


@hookimpl
def haptable_register_commands(register: Any) -> None:
    from . import cli

    register(
        "knob", cli.configure, cli.run, help="haptic knob: run the menu task, audition a condition"
    )


@hookimpl
def haptable_register_benchmarks(register: Any) -> None:
    def run(ctx: Any, quick: bool, report_dir: str | None = None) -> dict:
        from .bench import run as bench_run

        return bench_run(ctx, quick, report_dir=report_dir)

    register("knob", run, help="crossing-to-detent latency and synthesizer CPU per audio block")
