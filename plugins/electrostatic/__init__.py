"""Electrostatic friction and the haptic knob (paper 4.2, 5.3-5.5).

Registers: effects ``electrostatic`` (one friction stimulus with its expected force; its
``presets`` are the named friction settings) and ``knob`` (the four conditions and
variants, finite or live; its ``conditions`` names them); profile sections
[electrostatic] and [knob]; the ``haptable knob`` command; the ``knob`` benchmark; the
Electrostatic screen (panel ``electrostatic``, tab F5).
Modules: force (Eqs. 1-2, thresholds), rotation (two-finger tracker), knob (sectors),
synth (live stream), session/simulate (pipeline and twin), task (the experiment).
"""

from __future__ import annotations

from typing import Any

from console.plugin_api import PanelTab, hookimpl

from . import cli
from .effects import ElectrostaticEffect, KnobEffect
from .settings import ELECTROSTATIC_FIELDS, FRICTION_PRESETS, KNOB_FIELDS
from .synth import CONDITIONS


@hookimpl
def haptable_profile_sections(register: Any) -> None:
    register(
        "electrostatic",
        ELECTROSTATIC_FIELDS,
        help="electrovibration model (paper Eqs. 1-2) and detection thresholds",
    )
    register("knob", KNOB_FIELDS, help="haptic knob: sectors, feedback signals, tracker, task")


@hookimpl
def haptable_register_effects(register: Any) -> None:
    def electrostatic(profile: Any) -> Any:
        """``ElectrostaticEffect`` with ``presets`` (``FRICTION_PRESETS``)."""
        eff = ElectrostaticEffect(profile)
        eff.presets = {k: dict(v) for k, v in FRICTION_PRESETS.items()}
        return eff

    def knob(profile: Any) -> Any:
        """``KnobEffect`` with ``conditions``: the names ``render(condition=)`` takes."""
        eff = KnobEffect(profile)
        eff.conditions = tuple(CONDITIONS)
        return eff

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
def haptable_register_panels(register: Any) -> None:
    def electrostatic_panel(app: Any) -> Any:
        # lazy: Textual loads only with the console's panels
        from .panel import ElectrostaticPane

        return ElectrostaticPane()

    register(
        "electrostatic",
        electrostatic_panel,
        description="friction settings and knob conditions on the screen",
        tab=PanelTab("Electrostatic", "f5", 50),
    )


@hookimpl
def haptable_register_commands(register: Any) -> None:
    register(
        "knob", cli.configure, cli.run, help="haptic knob: run the menu task, audition a condition"
    )


@hookimpl
def haptable_register_benchmarks(register: Any) -> None:
    def run(ctx: Any, quick: bool, report_dir: str | None = None) -> dict:
        # lazy: bench loads when called, not at every haptable start
        from .bench import run as bench_run

        return bench_run(ctx, quick, report_dir=report_dir)

    register("knob", run, help="crossing-to-detent latency and synthesizer CPU per audio block")
