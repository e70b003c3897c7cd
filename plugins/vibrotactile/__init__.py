"""Localized vibrotactile feedback: vibration map I/O, interpolation, excitation lookup
tables, flow stimuli (between two points, under a hand) and the ``vibration`` benchmark.

Effects (``haptable_register_effects``): ``flow`` (between two points), ``hand_flow``
(under a hand) and ``point`` (a pulse); see ``plugins.vibrotactile.map_user`` for the
request vocabulary. The ``flow`` effect also gives the lookup tables (``tables(vmap=,
progress=)``, built step by step with progress and cancel; ``query(active, passive,
vmap=)``), ``prepare``/``cached`` and UFF import (``import_map({"PA": path, ...})``):
``plugins.vibrotactile.registered``. Commands: ``haptable frf import|export|info``,
``haptable tables build|query``, ``haptable flow``, ``haptable point``. Profile sections:
``[vibrotactile]`` and ``[perception]`` (the human threshold curve, as data).
"""

from __future__ import annotations

import importlib
from collections.abc import Callable
from typing import Any

from console.plugin_api import hookimpl

# each CLI module by another name: ``tables`` is a module of this package too
from plugins.vibrotactile.cli import flow as flow_cli
from plugins.vibrotactile.cli import frf as frf_cli
from plugins.vibrotactile.cli import selftest as selftest_cli
from plugins.vibrotactile.cli import tables as tables_cli
from plugins.vibrotactile.settings import sections


@hookimpl
def haptable_profile_sections(register) -> None:
    for name, (fields, help_) in sections().items():
        register(name, fields, help=help_)
    register("selftest", selftest_cli.SELFTEST_FIELDS, help="the technician's self-test")


@hookimpl
def haptable_register_effects(register) -> None:
    def effect(cls_name: str, module: str) -> Callable[[Any], Any]:
        """A factory of ``plugins.vibrotactile.<module>.<cls_name>(profile)``, the module
        imported on first use (numpy tables, SciPy)."""

        def factory(profile: Any) -> Any:
            return getattr(importlib.import_module(f"{__name__}.{module}"), cls_name)(profile)

        factory.__doc__ = f"``plugins.vibrotactile.{module}.{cls_name}(profile)``"
        return factory

    # flow also offers: tables(vmap=, progress=) (stepwise, cancellable: raise in
    # progress), query(active, passive, vmap=), prepare(pairs, vmap=, progress=),
    # cached(...), import_map({"PA": "pa.uff", ...}) -> VibrationMap (UFF 58)
    register(
        "flow",
        effect("RegisteredFlowEffect", "registered"),
        description="two-point flow (paper Fig. 9): render(from_point=, to_point=, vmap=|tables=)",
    )
    register(
        "hand_flow",
        effect("HandFlowEffect", "hand_flow_effect"),
        description="flow under a hand: render(center_mm=, direction=, vmap=, hand_mm=)",
    )
    register(
        "point",
        effect("PointEffect", "point_effect"),
        description="localized pulse at one point: render(point=, vmap=|tables=)",
    )
    register(
        "roving",
        effect("RovingEffect", "roving_console"),
        description="the roving-sensor map for the console (RovingSensorMaps): "
        "render(excitation=) one point's chirps",
    )


@hookimpl
def haptable_register_commands(register) -> None:
    register(
        "frf",
        frf_cli.configure_frf,
        frf_cli.run_frf,
        help="vibration map: import/export UFF 58, info",
    )
    register(
        "tables",
        tables_cli.configure_tables,
        tables_cli.run_tables,
        help="excitation lookup tables: build, query",
    )
    register(
        "flow",
        flow_cli.configure_flow,
        flow_cli.run_flow,
        help="vibrotactile flow between points or under a hand",
    )
    register(
        "point", flow_cli.configure_point, flow_cli.run_point, help="localized pulse at one point"
    )
    register(
        "selftest",
        selftest_cli.configure_selftest,
        selftest_cli.run_selftest_cmd,
        help="chirp every relay path at the reference point, compare with the baseline: "
        "dead channels, stuck relays, detached patches, swapped wires",
    )


@hookimpl
def haptable_register_benchmarks(register) -> None:
    def run(ctx, quick: bool, report_dir: str | None = None) -> dict:
        # lazy: bench loads when called, not at every haptable start
        from plugins.vibrotactile.bench import run_bench

        return run_bench(ctx, quick, report_dir=report_dir)

    register(
        "vibration",
        run,
        help="interpolation error vs time, table build/query, flow-under-hand precompute",
    )

    def run_instrument(ctx, quick: bool, report_dir: str | None = None) -> dict:
        # lazy: bench_instrument loads when called, not at every haptable start
        from plugins.vibrotactile.bench_instrument import run_instrument_bench

        return run_instrument_bench(ctx, quick)

    def run_selftest_bench(ctx, quick: bool, report_dir: str | None = None) -> dict:
        # lazy: bench_selftest loads when called, not at every haptable start
        from plugins.vibrotactile.bench_selftest import run_selftest_bench

        return run_selftest_bench(ctx, quick)

    register(
        "selftest",
        run_selftest_bench,
        help="self-test on twin tables with faults injected and healthy ones: found/named, "
        "false alarms, time",
    )
    register(
        "instrument",
        run_instrument,
        help="roving-accelerometer map (H1) on the twin vs its true FRFs: dB error per band "
        "where coherence >= 0.9, sensor mass on/off, lookup-table agreement, time per map",
    )
