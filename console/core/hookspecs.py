"""The HapTable plugin contract: every hook a plugin may implement, documented here.

A plugin is a module (or object) with functions decorated by ``@hookimpl`` whose names
are the hooks below. Every hook takes keyword arguments and a ``register`` callback;
the plugin calls ``register`` once per thing it provides. Built-in plugins use the same
hooks and the same manager as third-party ones (installed through the ``haptable``
entry-point group).

``register`` for the device and content kinds (cameras, classifiers, effects, audio
outputs, relay boards, scenes, projectors, panels) is a ``RegisterFactory``::

    register(name: str, factory: Callable[[Profile], object], *,
             description: str = "", probe: Callable[[Profile], DeviceStatus] | None = None,
             devices: Callable[[Profile], list[OutputDevice]] | None = None)

What a factory builds is typed in ``console.core.contracts`` (each hook below names its
Protocol); the plugin manager refuses a thing that lacks a member of its contract, with
one line naming the plugin, the kind and the member.

``name`` is what a profile's ``driver = "..."`` (or a scene list, or the console) uses to
pick it. ``factory(profile)`` builds the thing only when it is needed, so a driver's
hardware library is imported inside the factory, never at module import. ``probe``
lets ``haptable doctor`` say whether the device is there and what fixes it, without
opening it. ``devices`` (audio outputs only) lists what the driver could open, for the
console's Devices screen (``console.core.types.OutputDevice``: the name ``[audio] device``
takes, host API, channels, default latencies).

Every sample and relay switch produced by anything registered here goes through the
safety gate (``console.safety``); a plugin receives no handle to a driver.
"""

from __future__ import annotations

from collections.abc import Callable
from typing import Any, Protocol

import pluggy

from console.core.types import DeviceStatus

PROJECT = "haptable"
hookspec = pluggy.HookspecMarker(PROJECT)
hookimpl = pluggy.HookimplMarker(PROJECT)


class RegisterFactory(Protocol):
    """``register`` of the device and content kinds: one call per thing provided."""

    def __call__(
        self,
        name: str,
        factory: Callable[..., Any],
        *,
        description: str = "",
        probe: Callable[[Any], DeviceStatus] | None = None,
        tab: Any = None,  # panels only: a console.config.plugins.PanelTab
        devices: Callable[[Any], list[Any]] | None = None,  # audio outputs: OutputDevice
    ) -> None: ...


class RegisterCommand(Protocol):
    """``register`` of ``haptable_register_commands``."""

    def __call__(
        self,
        name: str,
        configure: Callable[[Any], None],
        run: Callable[[Any, Any], int],
        *,
        help: str = "",  # noqa: A002
    ) -> None: ...


class RegisterBenchmark(Protocol):
    """``register`` of ``haptable_register_benchmarks``."""

    def __call__(
        self,
        name: str,
        run: Callable[[Any, bool], dict],
        *,
        help: str = "",  # noqa: A002
    ) -> None: ...


class RegisterSection(Protocol):
    """``register`` of ``haptable_profile_sections``."""

    def __call__(
        self,
        section: str,
        fields: dict[str, Any],
        *,
        per_item: bool = False,
        help: str = "",  # noqa: A002
        check: Callable[[Any], None] | None = None,
    ) -> None: ...


#: Kept for plugins written against the untyped callback.
Register = RegisterFactory


@hookspec
def haptable_register_cameras(register: RegisterFactory) -> None:
    """Register camera drivers.

    The factory returns a ``contracts.Camera``: ``read(timeout_s) -> Frame | None``
    (640 x 480 uint8 by default), ``close()``, ``status() -> dict`` with at least
    ``fps`` and ``dropped``. Selected by ``[camera] driver`` in the profile. A simulated
    camera (the twin) is also a ``contracts.SimulatedCamera``: it acts out a
    ``GestureScript`` (``set_script``) and renders gesture samples offline, which is how
    other plugins script or render it without importing it; and a
    ``contracts.TouchableCamera`` (``set_target(pos_mm)``, ``mm_to_px(pos_mm)``): the
    operator's finger on the twin.
    """


@hookspec
def haptable_register_classifiers(register: RegisterFactory) -> None:
    """Register gesture classifiers.

    The factory returns a ``contracts.Classifier``: ``classify(window, t_s) -> Gesture |
    None`` (from its own vision results), ``gesture_stage()`` (the loop's ``classify``
    stage), ``names`` (the gestures it knows), ``n_frames``, the per-frame vision
    ``process(frame) -> contracts.VisionResult`` with its ``views``, ``to_mm``,
    ``set_background(image)`` and its tunables (``tunables()``, ``tunable_ranges()``,
    ``set_tunable(name, value)``). Selected by ``[gestures] classifier`` in the profile.

    Optionally a ``contracts.TouchCalibrating``: ``touch_calibration(profile) ->
    contracts.TouchCalibrationSession`` for the console's touch-calibration wizard
    (camera px -> table mm; the console says so when no classifier offers it).
    """


@hookspec
def haptable_register_effects(register: RegisterFactory) -> None:
    """Register effect renderers (vibrotactile, electrostatic ...).

    The factory returns a ``contracts.Effect``: ``render(**request) -> OutputPlan`` (a
    finite stimulus). Plans are in volts at the actuator; the safety gate refuses any
    plan out of limits.

    Optional capabilities the console asks for (``plugins.provider("effect", Protocol,
    profile)``; it says which plugin to enable when none offers one), all in
    ``console.core.contracts``: ``StreamingEffect`` (``stream(**request) -> StreamSource``),
    ``TableEffect`` (``tables``, ``query``), ``MapImporter`` (``import_map``),
    ``PointEffect`` (``render_point``), ``FlowEffect`` (``render_flow``),
    ``HandFlowEffect`` (``render_hand_flow``), ``Conditions`` (``conditions``) and
    ``Presets`` (``presets``).
    """


@hookspec
def haptable_register_audio_outputs(register: RegisterFactory) -> None:
    """Register audio output drivers (left channel: piezo amplifier, right: screen).

    The factory returns a ``contracts.AudioOutput`` (the twin's also a
    ``contracts.SimulatedAudio``): ``start(source)`` pulls blocks
    from ``source.fill(out)`` (the safety gate) until ``stop()``; ``status()`` reports
    ``latency_s`` and ``underruns``. Selected by ``[audio] driver``.
    """


@hookspec
def haptable_register_relay_boards(register: RegisterFactory) -> None:
    """Register relay board drivers.

    The factory returns a ``contracts.RelayBoard`` (the twin's also a
    ``contracts.SimulatedRelays``): ``channels``, ``set(channel,
    closed)``, ``states()``, ``close()``, ``status()``. Only the safety gate calls
    ``set``, and only while both output channels are silent. Selected by
    ``[relays] driver``.
    """


@hookspec
def haptable_register_vibrometers(register: RegisterFactory) -> None:
    """Register vibration-map measurement devices (a laser vibrometer, or the twin's).

    The factory returns a ``contracts.Vibrometer``: ``measure(progress=None) -> dict`` whose items are
    the arguments of ``console.files.vibration_map.make_map`` plus ``meta`` (provenance);
    ``progress(done, total)`` is called as the measurement advances; an exception raised
    by ``progress`` (an operator's cancel) stops it and propagates. Selected by
    ``[vibrometer] driver``.
    """


@hookspec
def haptable_register_scenes(register: RegisterFactory) -> None:
    """Register projected scenes.

    The factory returns a ``contracts.Scene`` with ``needs`` (what the runtime must prepare: e.g.
    ``{"tables": [...points], "flow_regions": [...], "knob": True, "contacts": True}``),
    ``update(event: dict) -> None`` and ``state() -> dict`` (JSON the projector draws).
    """


@hookspec
def haptable_register_projectors(register: RegisterFactory) -> None:
    """Register projector processes: how the console starts the one that draws scenes.

    The factory is a ``contracts.ProjectorFactory``: ``factory(profile, *, socket_path:
    Path, headless: bool = False, extra: list[str] = []) ->
    console.runtime.projector.supervisor.ProjectorLaunch``:
    ``argv``, the command line of a process that serves the projector link on
    ``socket_path`` (``console.runtime.projector.protocol``, the protocol both ends share)
    and, with ``headless``, renders offscreen; ``extra`` are further arguments for it;
    ``env``, variables added to its environment. The console's supervisor runs that
    command in its own session and restarts it when it dies or hangs. Selected by
    ``[projector] driver`` (default: the only one registered).
    """


@hookspec
def haptable_register_demos(register: RegisterFactory) -> None:
    """Register interactive demos the console can start (the paper's flow and knob).

    The factory is a ``contracts.DemoFactory``: it takes ``(profile, plugins, outputs,
    **params)`` instead of a profile and returns a running ``contracts.Demo`` with
    ``stop()``, ``snapshot() -> dict`` (camera, latency, watchdog and demo state as JSON
    values), ``scene_name`` and ``status_lines(snapshot)`` (what the operator reads of a
    snapshot; the factory formats one too, without a running demo). The console runs it in its
    own process (``console.runtime.demo_host``, a client of the console's table) and passes
    ``script=True``, ``camera_apart=True`` (a simulated camera may render in a process of
    its own), ``sinks=`` (frame sinks ``sink(frame, work)``), ``projector=`` (``update(event)``
    for the scene's events), ``progress(done, total, what)`` (raising stops the
    preparation) and ``vision=`` (the Camera screen's tuned thresholds); the demo's
    ``camera`` is a ``contracts.TouchableCamera`` when the operator can touch it.
    """


@hookspec
def haptable_register_frame_sinks(register: RegisterFactory) -> None:
    """Register frame sinks: outputs the frame loop feeds after its stages (e.g. TUIO).

    The factory is a ``contracts.FrameSinkFactory``: ``factory(profile, *, force=False)``
    returns a ``contracts.FrameSink``, or ``None`` when the profile leaves the sink off
    (``force`` opens it anyway, e.g. ``haptable demo --tuio``). A sink is called
    ``sink(frame, work)`` for every processed frame (``work``: the stages' results,
    ``contacts``, ``hands``, ``gesture`` ...), untimed, and its ``close()`` is called
    when the run ends.
    The demo runner opens every registered sink that the profile enables.
    """


@hookspec
def haptable_register_recording_readers(register: RegisterFactory) -> None:
    """Register readers of recorded runs in formats of their own (a study's trial files).

    The factory takes the profile and returns a ``contracts.RecordingReader``:
    ``reads(path) -> bool`` (whether the file is in its format, cheap) and
    ``open_recording(path) -> contracts.RecordedRun``. The console's Camera and Scope
    screens open a file with the first reader that reads it, else with the recorder's own
    (``contracts.ReadsRecordings``, a frame sink's).
    """


@hookspec
def haptable_register_observers(register: RegisterFactory) -> None:
    """Register simulated study participants (``haptable study run --simulate``).

    The factory takes the profile and returns a ``contracts.SimulatedObserver``:
    ``respond(trial, played, *, participant_seed) -> (response, response_time_s)`` for a
    plan's trial after the ``OutputPlan`` played, and ``parameters(participant_seed)``
    (stored with the participant). The studies plugin asks for the first one.
    """


@hookspec
def haptable_register_panels(register: RegisterFactory) -> None:
    """Register console panels (extra Textual screens).

    The factory is a ``contracts.PanelFactory``: it takes the running app instead of a
    profile and returns a Textual ``Screen`` (a ``contracts.Panel``); the console lists
    it in its command palette. With ``tab=console.config.plugins.PanelTab(title, key="f8",
    order=80)`` it is one of the console's tabs instead: the factory returns the tab's
    widget (a ``contracts.Panel`` too, built when the tab is first opened), ``key`` opens
    it, ``order`` places it (the built-in screens are Devices 10 ... Latency 70, keys
    f1-f7).
    """


@hookspec
def haptable_register_commands(register: RegisterCommand) -> None:
    """Register ``haptable`` sub-commands.

    ``register(name, configure, run, *, help="")``: ``configure(parser)`` adds the
    arguments to an ``argparse.ArgumentParser``; ``run(args, ctx) -> int`` does the work
    (``ctx`` gives the loaded profile and plugin manager) and returns the exit status.
    """


@hookspec
def haptable_register_benchmarks(register: RegisterBenchmark) -> None:
    """Register ``haptable bench NAME`` benchmarks.

    ``register(name, run, *, help="")``: ``run(ctx, quick: bool) -> dict`` returns the
    measured numbers (medians, p99, errors, machine); ``--json`` prints that dict.
    """


def documented_hooks() -> dict[str, Any]:
    """Every hook of the contract with its docstring (used by docs and tests)."""
    return {
        name: fn.__doc__
        for name, fn in globals().items()
        if name.startswith("haptable_") and callable(fn)
    }


@hookspec
def haptable_profile_sections(register: RegisterSection) -> None:
    """Declare the profile sections a plugin reads, so profiles are validated.

    ``register(section: str, fields: dict[str, console.core.schema.Field], *,
    per_item: bool = False, help: str = "", check=None)``. With ``per_item`` the section
    holds named sub-tables (``[patches.PA]``) that each have ``fields``. A key no plugin
    declares is an error naming the file and the closest known key. ``check(profile)``,
    when given, is called with the validated profile at load for what one key's ``Field``
    cannot see (a point id against ``[grid]``, a position against ``[table]``); it raises
    ``console.core.errors.UserError`` naming the key, and the load fails with that line
    prefixed by the file.
    """
