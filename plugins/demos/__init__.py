"""The paper's two demos end to end, and the interaction-loop benchmarks.

``haptable demo flow|knob``: camera -> vision -> gestures -> scene -> effect -> outputs,
on the twin (a scripted hand) or the real table. Benchmarks: ``haptable bench loop``
(per-stage and end-to-end latency) and ``haptable bench soak`` (long run: drops, RSS,
underruns). Profile sections: ``[runtime]`` (frame loop, watchdog) and ``[demos]``.

Console panel: the Scenes screen (``scenes``, tab F6; ``panel.py``).

The demos are registered through ``haptable_register_demos`` as ``flow`` and ``knob``:
``factory(profile, plugins, outputs, **params) -> DemoRun`` (``stop()``,
``snapshot()``, ``scene_name``, ``status_lines(snapshot)``; params as
``plugins.demos.run.start_demo``); the factory formats snapshots too
(``factory.status_lines``: the console holds only the snapshots of a demo run in
another process).
``start_demo(name, ...)`` is the same call by name (kept for compatibility).

Other plugins are reached only through registrations: effects ``hand_flow``, ``flow``
and ``knob``, the ``[vibrometer]`` driver (the twin's map), the camera and classifier
drivers and the ``flow_hand``/``knob`` scenes.
"""

from __future__ import annotations

from typing import Any

from console.plugin_api import Field, hookimpl

DEMOS = ("flow", "knob")

RUNTIME_FIELDS = {
    "watchdog_ms": Field(
        "float",
        250.0,
        min=20,
        max=10000,
        help="silence the outputs (e-stop) when the frame loop is stuck this long "
        "(a frame in one stage, or no frame from the camera)",
    ),
    "queue_frames": Field(
        "int", 2, min=1, max=64, help="frames waiting for processing; the oldest is dropped"
    ),
    "latency_window_frames": Field(
        "int", 1200, min=10, max=1000000, help="frames the latency monitor's p50/p99 cover"
    ),
    "realtime_loop": Field(
        "bool",
        True,
        help="a demo's frame loop threads ask for real-time (FIFO) scheduling one step "
        "below the audio thread, where the system allows it (rtprio limit or CAP_SYS_NICE)",
    ),
    "twin_camera_process": Field(
        "bool",
        True,
        help="demos on the twin camera: render its frames in a separate process, as a "
        "camera device delivers them (false: in the console's process, sharing its CPU time)",
    ),
}

DEMOS_FIELDS = {
    "flow_map": Field(
        "path",
        "",
        help="vibration map the flow demo uses (relative to the profile's folder); empty on "
        "the twin: the profile's measured map, measured once into HapTable's cache",
    ),
    "flow_direction": Field(
        "str", "right", choices=("left", "right", "up", "down"), help="flow direction"
    ),
    "flow_grid_mm": Field(
        "float",
        10.0,
        min=0,
        max=100,
        help="a hand away from the scene's regions gets the flow of the nearest point of "
        "this grid (0: its exact position)",
    ),
    "plan_process": Field(
        "bool",
        True,
        help="flows not prepared at the start (a hand away from the scene's regions) are "
        "planned in a separate process (false: on a thread sharing the loop's interpreter)",
    ),
    "flow_atlas": Field(
        "bool",
        True,
        help="when the flow demo prepares, choose every flow under a hand on the "
        "flow_grid_mm grid in every direction (minutes the first time, then cached): a "
        "resting hand's flow starts at once (false: planned when asked, 1-3 s late)",
    ),
    "still_mm": Field("float", 12.0, min=1, max=200, help="a resting hand moves less than this"),
    "still_ms": Field("float", 300.0, min=0, max=10000, help="... for this long to trigger"),
    "knob_condition": Field(
        "str", "HD+CF", help="knob feedback condition (V, HD, HD+CF, HD+VF, variants)"
    ),
}


@hookimpl
def haptable_profile_sections(register) -> None:
    register("runtime", RUNTIME_FIELDS, help="the interaction loop: queue, watchdog, monitor")
    register("demos", DEMOS_FIELDS, help="the flow and knob demos")


def start_demo(name: str, profile: Any, plugins: Any, outputs: Any, **params: Any):
    """Start a demo; see ``plugins.demos.run.start_demo``."""
    from .run import start_demo as _start

    return _start(name, profile, plugins, outputs, **params)


class DemoFactory:
    """A registered demo (``console.core.contracts.DemoFactory``): called ``(profile, plugins,
    outputs, **params)`` it starts the demo (``plugins.demos.run.start_demo``);
    ``status_lines(snapshot)`` formats a snapshot of it (``plugins.demos.status``)."""

    def __init__(self, name: str) -> None:
        self.name = name
        self.__doc__ = f"Start the {name} demo (``plugins.demos.run.start_demo``)."

    def __call__(self, profile: Any, plugins: Any, outputs: Any, **params: Any) -> Any:
        from .run import start_demo

        return start_demo(self.name, profile, plugins, outputs, **params)

    def status_lines(self, snapshot: dict[str, Any]) -> list[str]:
        from .status import status_lines

        return status_lines(snapshot)


def _demo_factory(name: str) -> DemoFactory:
    return DemoFactory(name)


@hookimpl
def haptable_register_demos(register) -> None:
    register(
        "flow",
        _demo_factory("flow"),
        description="flow under a resting hand, or between two resting index fingers",
    )
    register(
        "knob",
        _demo_factory("knob"),
        description="two-finger rotation of a virtual knob with haptic feedback",
    )


def _scenes_panel(app: Any) -> Any:
    from .panel import ScenesPane

    return ScenesPane()


@hookimpl
def haptable_register_panels(register) -> None:
    from console.plugin_api import PanelTab

    register(
        "scenes",
        _scenes_panel,
        description="scenes on the projector; the flow and knob demos on the outputs",
        tab=PanelTab("Scenes", "f6", 60),
    )


@hookimpl
def haptable_register_commands(register) -> None:
    from . import cli

    register(
        "demo",
        cli.configure,
        cli.run,
        help="run the flow or knob demo end to end (twin: a scripted hand)",
    )


@hookimpl
def haptable_register_benchmarks(register) -> None:
    def loop(ctx, quick: bool) -> dict:
        from .bench import run_loop

        return run_loop(ctx, quick)

    def soak(ctx, quick: bool, minutes: float | None = None) -> dict:
        from .bench import run_soak

        return run_soak(ctx, quick, minutes=minutes)

    def flow_latency(ctx, quick: bool) -> dict:
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
