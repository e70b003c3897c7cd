"""The paper's two demos end to end, and the interaction-loop benchmarks.

``haptable demo flow|knob``: camera -> vision -> gestures -> scene -> effect -> outputs,
on the twin (a scripted hand) or the real table. Benchmarks: ``haptable bench loop``
(per-stage and end-to-end latency) and ``haptable bench soak`` (long run: drops, RSS,
underruns). Profile sections (``settings.py``): ``[runtime]`` (frame loop, watchdog)
and ``[demos]``. The registered demo factory: ``factory.py``.

Console panel: the Scenes screen (``scenes``, tab F6; ``panel.py``).

The demos are registered through ``haptable_register_demos`` as ``flow`` and ``knob``:
``factory(profile, plugins, outputs, **params) -> DemoRun`` (``stop()``,
``snapshot()``, ``scene_name``, ``status_lines(snapshot)``; params as
``plugins.demos.run.start_demo``); the factory formats snapshots too
(``factory.status_lines``: the console holds only the snapshots of a demo run in
another process).

Other plugins are reached only through registrations: effects ``hand_flow``, ``flow``
and ``knob``, the ``[vibrometer]`` driver (the twin's map), the camera and classifier
drivers and the ``flow_hand``/``knob`` scenes.
"""

from __future__ import annotations

from typing import Any

from console.plugin_api import PanelTab, hookimpl

from . import cli
from .factory import DemoFactory
from .settings import DEMOS_FIELDS, RUNTIME_FIELDS


@hookimpl
def haptable_profile_sections(register) -> None:
    register("runtime", RUNTIME_FIELDS, help="the interaction loop: queue, watchdog, monitor")
    register("demos", DEMOS_FIELDS, help="the flow and knob demos")


@hookimpl
def haptable_register_demos(register) -> None:
    register(
        "flow",
        DemoFactory("flow"),
        description="flow under a resting hand, or between two resting index fingers",
    )
    register(
        "knob",
        DemoFactory("knob"),
        description="two-finger rotation of a virtual knob with haptic feedback",
    )


@hookimpl
def haptable_register_panels(register) -> None:
    def scenes_panel(app: Any) -> Any:
        # lazy: Textual loads only with the console's panels
        from .panel import ScenesPane

        return ScenesPane()

    register(
        "scenes",
        scenes_panel,
        description="scenes on the projector; the flow and knob demos on the outputs",
        tab=PanelTab("Scenes", "f6", 60),
    )


@hookimpl
def haptable_register_commands(register) -> None:
    register(
        "demo",
        cli.configure,
        cli.run,
        help="run the flow or knob demo end to end (twin: a scripted hand)",
    )


@hookimpl
def haptable_register_benchmarks(register) -> None:
    def loop(ctx, quick: bool) -> dict:
        # lazy: bench loads when called, not at every haptable start
        from .bench import run_loop

        return run_loop(ctx, quick)

    def soak(ctx, quick: bool, minutes: float | None = None) -> dict:
        # lazy: bench loads when called, not at every haptable start
        from .bench import run_soak

        return run_soak(ctx, quick, minutes=minutes)

    def flow_latency(ctx, quick: bool) -> dict:
        # lazy: flow_latency loads when called, not at every haptable start
        from .flow_latency import run_flow_latency

        return run_flow_latency(ctx, quick)

    register(
        "flow-latency",
        flow_latency,
        help="flow demo: gesture decision -> the flow's first sample at the driver, p50/p99, "
        "with every flow chosen ahead (after) and searched when asked (before); the "
        "precompute's time and memory",
    )
    register(
        "loop",
        loop,
        help="frame arrival -> first output sample scheduled: per-stage and end-to-end p50/p99",
    )
    register(
        "soak",
        soak,
        help="knob demo for 10 minutes at 60 fps: dropped frames, RSS, underruns, watchdog "
        "trips (other lengths: haptable demo soak --minutes N, or HAPTABLE_SOAK_MINUTES)",
    )
