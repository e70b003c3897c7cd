"""Recordings of runs that replay: the camera's frames (lossless), each frame's vision
results, gesture, scene state and plan, in one HDF5 file.

Off by default. Profile section ``[recording]``: ``enabled``, ``path`` (empty: a new file
under HapTable's data directory), ``codec`` (``lzf`` or ``gzip1``), ``queue_frames``,
``flush_s``, ``replay_file`` (the camera ``replay``), ``study_trials`` (the studies plugin
records each trial: ``haptable study run ... --record``). ``haptable demo NAME --record FILE``
records one run. The recorder is the frame sink ``recording``
(``haptable_register_frame_sinks``): it copies each frame into a bounded queue (a full
queue drops the frame and counts it) and a writer thread compresses and writes in SWMR
mode, flushed every ``flush_s``, so a killed run leaves a readable file.

File layout (``format`` = ``haptable-recording``, ``format_version`` 1, root attributes
also ``versions``, ``profile_name``, ``profile_json``, ``profile_toml``, ``demo``,
``tunables``, ``codec``, ``created_utc``): ``frames`` (N, H, W) uint8 one chunk per
frame; ``seq``, ``t_capture_s`` (N,); ``decisions`` the frames' decisions as JSON bytes,
``decisions_index`` (N, 2) offset and length of each; ``plans`` plans played off the
frame loop (JSON lines); ``gate_events`` the kernel's own events during the run (rows of
time, gate clock, kind, message: relay switches, e-stops, resets, faults, refusals;
``console.core.gate_log``); ``background`` the learned empty table; ``stats`` (written,
dropped).

``haptable replay FILE`` runs the frames through the same vision and gesture stages and
says whether every decision comes out the same. ``haptable bench recording``: write rate,
bytes per frame and dropped frames at 60 fps.

Modules: ``settings``, ``decisions`` (a frame's decisions as JSON, ``plan_hash``),
``writer`` (``Recorder``), ``sink`` (``make_recorder``), ``reader`` (``open_recording``),
``camera`` (``ReplayCamera``, the driver ``replay``), ``readback`` (the sink's factory,
which also reads a recording back for the console's Camera and Scope screens), ``replay`` (``--vision-only``),
``replay_demo`` (through the demo), ``cli``, ``bench``.
"""

from __future__ import annotations

from console.plugin_api import hookimpl

from . import camera, cli
from .camera import open_replay_camera
from .settings import FIELDS


@hookimpl
def haptable_profile_sections(register) -> None:
    register("recording", FIELDS, help="record runs (frames, decisions, plans) into HDF5")


@hookimpl
def haptable_register_frame_sinks(register) -> None:
    # lazy: loaded when this runs, not when the module is imported
    from .readback import RecorderFactory  # light: the recorder and reader load when used

    register(
        "recording",
        RecorderFactory(),
        description="frames, vision, gestures, plans into an HDF5 file ([recording] enabled)",
    )


@hookimpl
def haptable_register_cameras(register) -> None:
    register(
        "replay",
        open_replay_camera,
        description="a recording's frames ([recording] replay_file)",
        probe=camera.probe,
    )


@hookimpl
def haptable_register_commands(register) -> None:
    register(
        "replay",
        cli.configure,
        cli.run,
        help="replay a recording through vision and gestures: every decision the same?",
    )


@hookimpl
def haptable_register_benchmarks(register) -> None:
    def recording(ctx, quick: bool, minutes: float | None = None) -> dict:
        from .bench import run  # lazy: loads when called

        return run(ctx, quick, minutes=minutes)

    register(
        "recording",
        recording,
        help="recording at 60 fps for --minutes (1; quick: 10 s): write rate, bytes per "
        "frame, frames dropped, per codec, with the machine",
    )
