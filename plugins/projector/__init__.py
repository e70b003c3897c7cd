"""Projected scenes: a separate projector process (pyglet + moderngl, or EGL headless)
driven from the console over a Unix-socket link (``console.runtime.projector``; this
plugin serves it in ``server`` and registers how it is started in ``launch``).

Scenes are registered here (``haptable_register_scenes``), drawn in table millimetres
(``draw``) through the projector calibration (``geometry``), and rendered by
``renderer``. Heavy libraries (moderngl, pyglet, cv2) are imported inside functions.
"""

from __future__ import annotations

from console.plugin_api import hookimpl
from plugins.projector import cli
from plugins.projector.launch import DESCRIPTION, NAME
from plugins.projector.launch import launch as launch_projector
from plugins.projector.scenes import BUILTIN_SCENES
from plugins.projector.settings import FIELDS, check_profile


@hookimpl
def haptable_register_scenes(register) -> None:
    for name, (cls, description) in BUILTIN_SCENES.items():
        register(name, cls, description=description)


@hookimpl
def haptable_register_projectors(register) -> None:
    register(NAME, launch_projector, description=DESCRIPTION)


@hookimpl
def haptable_profile_sections(register) -> None:
    register(
        "projector",
        FIELDS,
        help="the projector process, its link, calibration and scene layout",
        check=check_profile,
    )


@hookimpl
def haptable_register_commands(register) -> None:
    register(
        "projector",
        cli.configure,
        cli.run,
        help="projector: full-screen scenes, screenshots, calibration",
    )


@hookimpl
def haptable_register_benchmarks(register) -> None:
    def run(ctx, quick: bool) -> dict:
        # lazy: bench loads when called, not at every haptable start
        from plugins.projector.bench import run_bench

        return run_bench(ctx, quick)

    register("projector", run, help="frame time per scene at 1920x1080 headless; link latency")
