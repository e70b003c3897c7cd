"""What crosses a plugin boundary, typed: the Protocols registered objects satisfy.

``console/core/hookspecs.py`` says which hooks a plugin implements and what it registers;
this module says what the registered things *are*. Every registered factory builds an
object satisfying the Protocol of its kind (``KIND_CONTRACTS``); some objects also offer
an optional capability (a narrower Protocol). console/ asks for a capability
(``plugins.provider("effect", PointEffect, profile)``) instead of an effect's name, a
snapshot's keys or another plugin's internals, and the plugin manager refuses an object
that lacks a member of its kind's contract with one line naming the plugin, the kind and
the member (``check``).

Capabilities at a glance (kind: the contract, then the optional capabilities)::

    camera        Camera; AdjustableCamera (exposure, gain); TouchableCamera (the operator's finger on a twin),
                  RendersBackground, SimulatedCamera (acts out GestureScripts)
    classifier    Classifier (gestures, per-frame vision, tunables, background);
                  TouchCalibrating (the touch-calibration wizard's session);
                  TunablesInProfile (the profile keys its tunables are kept under),
                  OrderedTunables (the order its tunables keep)
    effect        Effect; StreamingEffect, TableEffect, MapImporter, PointEffect,
                  FlowEffect, FlowPatchDrives, HandFlowEffect, HandFlowGeometry,
                  PrecomputedHandFlows, Conditions, Presets; RovingSensorMaps (roving_contracts)
    audio_output  AudioOutput; SimulatedAudio (the twin: paced, recording_v);
                  RecordsUnderruns (the twin: its underrun log)
    relay_board   RelayBoard; SimulatedRelays (the twin: switch log)
    vibrometer    Vibrometer
    scene         Scene (its events: e.g. PointsEvent)
    projector     ProjectorFactory -> ProjectorLauncher
    demo          DemoFactory -> Demo (with its own status_lines)
    frame_sink    FrameSinkFactory -> FrameSink; ReadsRecordings (reads a recorded run back:
                  the Camera and Scope screens show it); SwitchableSink (its switch and target
                  in the profile: the Camera screen turns it on and off)
    panel         PanelFactory -> Panel
    observer      SimulatedObserver (a simulated study participant)
    recording_reader  RecordingReader (a recorded run in a format of its own: a study trial;
                  KeepsItsMap: the map its plans were rendered on, re-rendered on Scope)

Values that cross (frames, gestures, plans ...) are the dataclasses of
``console.core.types``; only behaviour is typed here.
"""

from __future__ import annotations

from collections.abc import Callable, Mapping, Sequence
from typing import Any, Literal, Protocol, TypedDict, runtime_checkable

import numpy as np

from console.core.recording_contracts import BeginsRun as BeginsRun
from console.core.recording_contracts import KeepsItsMap as KeepsItsMap
from console.core.recording_contracts import ReadsRecordings as ReadsRecordings
from console.core.recording_contracts import RecordedRun as RecordedRun
from console.core.recording_contracts import RecordingReader
from console.core.recording_contracts import WatchesOutputs as WatchesOutputs
from console.core.roving_contracts import RovingSensorMaps as RovingSensorMaps
from console.core.sink_contracts import AdvisesInField as AdvisesInField

# the frame sinks' and panels' contracts: here too, where every kind's contract is found
from console.core.sink_contracts import FrameSink, FrameSinkFactory, Panel, PanelFactory
from console.core.sink_contracts import SwitchableSink as SwitchableSink
from console.core.tuning_contracts import OrderedTunables as OrderedTunables
from console.core.tuning_contracts import TunablesInProfile as TunablesInProfile
from console.core.types import (
    Contact,
    Frame,
    Gesture,
    GestureScript,
    Hand,
    OutputPlan,
    TunableRange,
)

PosMm = tuple[float, float]


# --------------------------------------------------------------------------- outputs
@runtime_checkable
class ParametricStream(Protocol):
    """What outputs play as a live stream: ``spec`` (a ``console.signals.stream_synth.StreamSpec``)
    is what the table's kernel synthesises, and ``bind(sink)`` makes the source post its
    targets and crossings to the kernel's side (``sink.post(ids, carrier_hz, carrier_v)``,
    ``sink.request_stop()``). No plugin code runs on the audio path."""

    @property
    def spec(self) -> Any: ...

    def bind(self, sink: Any) -> None: ...


@runtime_checkable
class StreamSource(ParametricStream, Protocol):
    """A live output (e.g. the knob) a ``StreamingEffect`` gives: parameters for the
    outputs (``ParametricStream``), and ``next_block`` renders it locally (offline: the
    twin, tests) until it is bound."""

    patches: frozenset[str]
    screen: bool

    def next_block(self, n: int) -> tuple[np.ndarray, np.ndarray] | None: ...

    def request_stop(self) -> None: ...


@runtime_checkable
class BlockSource(Protocol):
    """What an audio output pulls from: the safety gate. Fills ``out`` (frames, channels),
    float32 sound-card units in [-1, 1], one column per ``[audio] channels`` name (by
    default two: column 0 = left (piezo), 1 = right (screen))."""

    def fill(self, out: np.ndarray) -> None: ...

    @property
    def idle(self) -> bool: ...

    def estop(self, reason: str) -> None:
        """Drivers call this when the device fails (vanished, stream error)."""


@runtime_checkable
class AudioOutput(Protocol):
    """An audio device (left channel: piezo amplifier, right: screen). It never generates
    samples itself: ``start(source)`` pulls blocks from ``source.fill`` (the safety gate)
    until ``stop()``; ``status()`` reports ``latency_s`` and ``underruns``."""

    sample_rate_hz: int
    block_size: int

    def start(self, source: BlockSource) -> None: ...

    def stop(self) -> None: ...

    def status(self) -> dict[str, Any]: ...


@runtime_checkable
class SimulatedAudio(AudioOutput, Protocol):
    """A simulated sound card (the twin): ``paced`` (True: blocks at the card's rate;
    False: as fast as the gate fills them, for tests and offline runs) and what it
    played, in volts at the actuator (``recording_v() -> (n, channels)``)."""

    paced: bool

    def recording_v(self) -> np.ndarray: ...


@runtime_checkable
class RecordsUnderruns(Protocol):
    """A simulated card that logs its underruns (the twin): ``underrun_log`` (records
    with ``clock``: the gap fell before that sample of the recording, and ``samples``),
    and ``dac_output_card()``: the recording with the gaps inserted, card units."""

    underrun_log: Any

    def dac_output_card(self) -> np.ndarray: ...


@runtime_checkable
class RelayBoard(Protocol):
    """A relay board; channels are 1-based. Only the safety gate calls ``set``, and only
    while both output channels are silent."""

    channels: int

    def set(self, channel: int, closed: bool) -> None: ...

    def states(self) -> tuple[bool, ...]: ...

    def close(self) -> None: ...

    def status(self) -> dict[str, Any]: ...


@runtime_checkable
class SimulatedRelays(RelayBoard, Protocol):
    """A simulated relay board (the twin) keeps ``log``: every switch, in order
    (records with ``t_s``, ``channel``, ``closed`` and the output level then)."""

    log: list[Any]


# --------------------------------------------------------------------------- camera
@runtime_checkable
class Camera(Protocol):
    """A camera: ``read`` returns the next frame (640 x 480 uint8 by default) or ``None``
    if none is ready; ``status()`` has at least ``fps`` and ``dropped``."""

    def read(self, timeout_s: float = 0.1) -> Frame | None: ...

    def close(self) -> None: ...

    def status(self) -> dict[str, Any]: ...


@runtime_checkable
class TouchableCamera(Camera, Protocol):
    """A camera the operator can touch (a twin): ``set_target(pos_mm)`` puts a fingertip
    on the table at ``pos_mm`` (``None`` lifts it); ``mm_to_px(pos_mm)`` is where a table
    point shows in the image (``None`` outside it), for drawing targets on the view."""

    def set_target(self, pos_mm: PosMm | None) -> None: ...

    def mm_to_px(self, pos_mm: PosMm) -> tuple[float, float] | None: ...


@runtime_checkable
class AdjustableCamera(Camera, Protocol):
    """A camera whose driver takes exposure, gain ... while it runs (the Camera screen
    tunes them): ``controls() -> {name: TunableRange}``, ``control_values()``,
    ``set_control(name, value)`` (from the next frames), ``control_keys() -> {name:
    profile key}`` (where they are kept). A camera that is not one has none."""

    def controls(self) -> dict[str, TunableRange]: ...

    def control_values(self) -> dict[str, float]: ...

    def control_keys(self) -> dict[str, str]: ...

    def set_control(self, name: str, value: float) -> None: ...


@runtime_checkable
class RendersBackground(Camera, Protocol):
    """A camera that can show its empty table (``background() -> (H, W)`` image) even
    with hands on it, so the vision learns the background at once."""

    def background(self) -> np.ndarray: ...


@runtime_checkable
class SimulatedCamera(RendersBackground, Protocol):
    """A camera that renders on request (the camera twin).

    ``set_script(GestureScript)`` shows a scripted hand on the live stream from the next
    frame on (``None``: back to the camera's own script, the profile's); ``place(gesture,
    center_mm)`` holds a static gesture still with its palm centre at ``center_mm``; ``render_sample(gesture, subject, rep, rng, *, n_frames=None, t0_s=None,
    side=None, subject_seed=None, subject_change=None) -> (frames (n, H, W) uint8, truth
    dict)`` renders one performance offline (dataset synthesis; ``subject_change`` a
    function of the simulated subject, for randomised sets); ``render_background(t_s, rng)`` the empty
    table at session time ``t_s``; ``mapping`` the table mm <-> px mapping (``to_dict()``).
    A real camera is none of this: the operator's hand does it.
    """

    @property
    def mapping(self) -> Any: ...

    def set_script(self, script: GestureScript | None) -> None: ...

    def place(self, gesture: str, center_mm: PosMm) -> None: ...

    def render_sample(
        self, gesture: str, subject: str, rep: int, rng: np.random.Generator, **kw: Any
    ) -> tuple[np.ndarray, dict[str, Any]]: ...

    def render_background(self, t_s: float, rng: np.random.Generator) -> np.ndarray: ...


# --------------------------------------------------------------------------- vision
@runtime_checkable
class VisionResult(Protocol):
    """What a classifier's vision found in one frame: ``hands``, ``contacts`` (all contact
    blobs, on a hand or not), its intermediate images by name (``view(name)``, one of
    the classifier's ``views``; ``None`` when it has no such image) and what it measured
    that an operator tunes against (``readings() -> {name: value}``, e.g. the touching
    skin's level, ``touching mm2`` the main hand's skin on the glass (a flat hand's too,
    which leaves no fingertip contact), or pixels the sensor clips; may be empty)."""

    hands: tuple[Hand, ...]
    contacts: tuple[Contact, ...]

    def view(self, name: str) -> np.ndarray | None: ...

    def readings(self) -> dict[str, float]: ...


@runtime_checkable
class Classifier(Protocol):
    """A gesture classifier with its per-frame vision.

    - ``names``: the gestures it knows; ``classify(window, t_s) -> Gesture | None``
      decides from the first ``n_frames`` ``VisionResult``s its ``process`` gave, in
      frame order, none processed again (``t_s``: the gesture's time; ``n_frames == 0``:
      no trained model, it names nothing).
    - ``process(frame) -> VisionResult``: one frame through the vision, once (stamps
      ``vision`` on the frame); ``views``: the names its results' ``view`` knows.
    - ``gesture_stage(*, still_mm, still_s)``: the loop's ``classify`` stage, the gesture
      rules (its ``work`` keys: ``console.runtime.stages``).
    - ``to_mm``: camera px -> table mm, ``(n, 2) -> (n, 2)``, or ``None`` (positions stay
      in pixels; the console may set a fallback).
    - ``set_background(image)``: the empty table, learnt at once.
    - tunables (the Camera screen's thresholds): ``tunables() -> {name: value}``,
      ``tunable_ranges() -> {name: TunableRange}``, ``set_tunable(name, value)`` (the
      next frame uses it; a name it has not or a value out of range is a ``ValueError``).
    """

    names: tuple[str, ...]
    views: tuple[str, ...]
    to_mm: Callable[[np.ndarray], np.ndarray] | None

    @property
    def n_frames(self) -> int: ...

    def classify(self, window: Sequence[VisionResult], t_s: float) -> Gesture | None: ...

    def gesture_stage(
        self, *, still_mm: float = 12.0, still_s: float = 0.3
    ) -> Callable[[Frame, dict], Any]: ...

    def process(self, frame: Frame) -> VisionResult: ...

    def set_background(self, image: np.ndarray) -> None: ...

    def tunables(self) -> dict[str, float]: ...

    def tunable_ranges(self) -> dict[str, TunableRange]: ...

    def set_tunable(self, name: str, value: float) -> None: ...


@runtime_checkable
class CalibrationResult(Protocol):
    """A finished touch calibration: ``report()`` has ``pairs``, ``rms_mm``, ``max_mm``,
    ``loo_rms_mm``, ``outliers``; ``save(path)`` writes the file ``[vision] calibration``
    names."""

    def report(self) -> dict[str, Any]: ...

    def save(self, path: Any) -> Any: ...


@runtime_checkable
class TouchCalibrationSession(Protocol):
    """The wizard's session (camera px -> table mm): ``targets_mm`` (N x 2);
    ``next_target() -> (index, (x, y) mm) | None``; ``feed(contacts) -> event`` for each
    frame's contacts (``"recorded"``, ``"lifted"``, ``"done"``, or a waiting state);
    ``skip()``; ``index``; ``state`` (``"done"`` at the end); ``progress() -> (touched,
    total)``; ``finish() -> CalibrationResult``."""

    targets_mm: np.ndarray
    index: int
    state: str

    def next_target(self) -> tuple[int, PosMm] | None: ...

    def feed(self, contacts: Sequence[Contact]) -> str: ...

    def skip(self) -> None: ...

    def progress(self) -> tuple[int, int]: ...

    def finish(self) -> CalibrationResult: ...


@runtime_checkable
class TouchCalibrating(Protocol):
    """A classifier offering the touch-calibration wizard (the console says so when none
    does): ``touch_calibration(profile) -> TouchCalibrationSession``."""

    def touch_calibration(self, profile: Any) -> TouchCalibrationSession: ...


@runtime_checkable
class ReportsProblem(Protocol):
    """A plugin that runs with less than its settings ask says why: ``problem``, the
    ``UserError`` (a ``console.core.words.Placed`` one carries the fix per place) or
    ``None`` (e.g. a classifier whose saved model does not fit: the vision runs, no
    gesture is named)."""

    problem: Exception | None


# --------------------------------------------------------------------------- effects
@runtime_checkable
class Effect(Protocol):
    """An effect renderer: ``render(**request) -> OutputPlan``, a finite stimulus in volts
    at the actuator (the safety gate refuses any plan out of limits). The keywords are
    the effect's own (its registration's description names them)."""

    def render(self, **request: Any) -> OutputPlan: ...


@runtime_checkable
class StreamingEffect(Effect, Protocol):
    """An effect that also plays live: ``stream(**request) -> StreamSource``."""

    def stream(self, **request: Any) -> StreamSource: ...


@runtime_checkable
class TableEffect(Effect, Protocol):
    """Lookup tables of a vibration map: the best excitation per pair (paper Fig. 8).

    ``tables(vmap=, progress=None)`` builds (or loads) them; ``progress(fraction,
    message)`` is called between build steps and may raise to cancel the build.
    ``query(active, passive, vmap=) -> dict`` gives a pair's entry
    (``max_difference_um_per_v``, ``frequency_hz``, ``actuator``)."""

    def tables(
        self, vmap: Any = None, *, progress: Callable[[float, str], None] | None = None
    ) -> Any: ...

    def query(self, active: int, passive: int, *, vmap: Any = None) -> dict[str, Any]: ...


@runtime_checkable
class MapImporter(Protocol):
    """Vibration maps from measurement files (imports UFF 58): ``import_map(files) ->
    VibrationMap``, one file per excitation (e.g. ``{"PA": "pa.uff"}``)."""

    def import_map(self, files: Mapping[str, Any]) -> Any: ...


@runtime_checkable
class PointEffect(Effect, Protocol):
    """A localized point stimulus: a pulse at one grid point (or ``(x, y)`` mm) of the
    map ``vmap``."""

    def render_point(self, point: Any, vmap: Any) -> OutputPlan: ...


@runtime_checkable
class FlowEffect(Effect, Protocol):
    """A two-point flow: from grid point ``a`` to grid point ``b`` of the map ``vmap``
    (Fig. 9). The plan's ``meta`` (``console.core.types.PlanInfo``) says how it was rendered:
    ``method``, ``predicted_contrast_db``, ``rule``, ``parts``."""

    def render_flow(self, a: int, b: int, vmap: Any) -> OutputPlan: ...


@runtime_checkable
class HandFlowEffect(Effect, Protocol):
    """A flow under a hand: centred at ``center_mm``, toward ``direction`` (a key of
    ``console.core.types.DIRECTIONS_MM``), on the map ``vmap``."""

    def render_hand_flow(self, center_mm: PosMm, direction: str, vmap: Any) -> OutputPlan: ...


@runtime_checkable
class FlowPatchDrives(FlowEffect, Protocol):
    """A two-point flow effect that says how it drives each patch:
    ``patch_drives(pairs, vmap=, method=)`` -> per (active, passive) pair of map
    indices a dict (``frequency_hz``, ``weights`` (4,) complex, ``amplitude_v``,
    ``x_um``) or ``None`` where no flow serves (``method``: ``paper`` or
    ``independent``). The twin's localisation and loop checks play these."""

    def patch_drives(
        self, pairs: Any, *, vmap: Any = None, method: str = "independent"
    ) -> list[dict | None]: ...


@runtime_checkable
class HandFlowGeometry(HandFlowEffect, Protocol):
    """A flow-under-hand effect that shows its geometry: ``patch_drives(center_mm,
    direction, vmap=, method=, hand_mm=)`` (the two parts as per-patch drives),
    ``sides(direction)`` (start and end side square masks), ``square_levels_um_per_v(
    center_mm, actuator, frequency_hz, vmap=)`` (each square's level per volt) and
    ``region_centers(step_mm, vmap=)`` (the hand centres the map serves)."""

    def patch_drives(
        self,
        center_mm: PosMm,
        direction: str,
        *,
        vmap: Any = None,
        method: str = "independent",
        hand_mm: float | None = None,
    ) -> list[dict]: ...

    def sides(self, direction: str) -> tuple[Any, Any]: ...

    def square_levels_um_per_v(
        self, center_mm: PosMm, actuator: str, frequency_hz: float, *, vmap: Any = None
    ) -> Any: ...

    def region_centers(self, step_mm: float, *, vmap: Any = None) -> list: ...


@runtime_checkable
class HandFlowAtlas(Protocol):
    """Every flow under a hand on a grid of centres, chosen ahead: ``nearest(pos_mm)`` the
    centre serving a hand there (``None``: outside), ``has(center_mm)``,
    ``plan(center_mm, direction)`` its plan (``UserError``: no flow there), ``nbytes``."""

    nbytes: int

    def nearest(self, pos_mm: PosMm) -> tuple[float, float] | None: ...

    def has(self, center_mm: PosMm) -> bool: ...

    def plan(self, center_mm: PosMm, direction: str) -> OutputPlan: ...


@runtime_checkable
class PrecomputedHandFlows(HandFlowEffect, Protocol):
    """A flow-under-hand effect that chooses every flow of a map ahead:
    ``hand_flow_atlas(vmap, step_mm, progress=, partial=, focus=)`` (``progress(done,
    total, what)``; raising cancels) -> ``HandFlowAtlas``, the same plans
    ``render_hand_flow`` gives at its centres. While it is built, ``partial(atlas)`` gets
    the atlas whose ``has`` is true of the places searched so far, the place ``focus()``
    returns (a hand's, or ``None``) searched next."""

    def hand_flow_atlas(
        self,
        vmap: Any,
        step_mm: float,
        *,
        progress: Any = None,
        partial: Any = None,
        focus: Any = None,
    ) -> HandFlowAtlas: ...


@runtime_checkable
class Conditions(Effect, Protocol):
    """Named conditions: the ``conditions`` that ``render(condition=)`` (and ``stream``)
    take, in order."""

    conditions: tuple[str, ...]


@runtime_checkable
class Presets(Effect, Protocol):
    """Named presets: settings an operator may audition, ``render`` keywords (``vpp``,
    ``freq_hz``, ``waveform`` ...) plus ``help``."""

    presets: dict[str, dict[str, Any]]


# --------------------------------------------------------------------------- scenes
class PointsEvent(TypedDict):
    """The event telling a grid scene the map's own points: ``{"type": "points", "ids":
    [n, ...], "points_mm": [[x, y], ...]}`` (the ids the map numbers, where they are)."""

    type: Literal["points"]
    ids: list[int]
    points_mm: list[list[float]]


def points_event(ids: Sequence[int], points_mm: Any) -> PointsEvent:
    """A ``PointsEvent`` from ids and an (n, 2) array of millimetres."""
    pts = np.asarray(points_mm, dtype=float).reshape(-1, 2)
    return {"type": "points", "ids": [int(i) for i in ids], "points_mm": pts.tolist()}


@runtime_checkable
class Scene(Protocol):
    """A projected scene: ``needs`` (what the runtime must prepare: e.g. ``{"tables":
    [...points] | "map", "flow_regions": [...], "knob": True, "contacts": True}``),
    ``update(event: dict)`` (``set`` events overwrite fields; a ``PointsEvent``; the
    scene's own events) and ``state() -> dict`` (the JSON the projector draws)."""

    @property
    def needs(self) -> dict[str, Any]: ...

    def update(self, event: dict[str, Any]) -> None: ...

    def state(self) -> dict[str, Any]: ...


# --------------------------------------------------------------------------- projector
@runtime_checkable
class ProjectorLauncher(Protocol):
    """How to start a projector process (``console.runtime.projector.supervisor.
    ProjectorLaunch``): ``argv``, a command line serving the projector link, and its
    ``environment()`` (``None``: the console's own)."""

    argv: Sequence[str]

    def environment(self) -> dict[str, str] | None: ...


@runtime_checkable
class ProjectorFactory(Protocol):
    """``factory(profile, *, socket_path, headless=False, extra=()) ->
    ProjectorLauncher``: the projector serving ``socket_path``."""

    def __call__(
        self, profile: Any, *, socket_path: Any, headless: bool = False, extra: Any = ()
    ) -> ProjectorLauncher: ...


# --------------------------------------------------------------------------- demos
@runtime_checkable
class Demo(Protocol):
    """A running demo: ``stop()`` (safe twice), ``snapshot() -> dict`` (camera, latency,
    watchdog and demo state as JSON values; ``off_loop``, when present, the outputs played
    once planned outside the frame loop: ``n`` and their planning ms, which Latency and
    Scenes count apart), ``scene_name`` (the scene to project),
    ``camera`` (a ``TouchableCamera`` when the operator can touch it) and
    ``status_lines(snapshot) -> list[str]``: what the operator reads of a snapshot
    (Textual markup), so the console never decodes a demo's keys."""

    @property
    def scene_name(self) -> str: ...

    @property
    def camera(self) -> Any: ...

    def stop(self) -> None: ...

    def snapshot(self) -> dict[str, Any]: ...

    def status_lines(self, snapshot: dict[str, Any]) -> list[str]: ...


@runtime_checkable
class DemoFactory(Protocol):
    """How a demo is registered: called ``(profile, plugins, outputs, **params)`` it
    starts one (``Demo``); ``status_lines(snapshot)`` formats a snapshot without a running
    demo (the console's process holds only the snapshots of a demo run elsewhere).
    A snapshot's ``hand`` (what the camera saw: ``hands``, ``contacts``, ``gesture``,
    ``rest_mm``), when present, is shown too."""

    def __call__(self, profile: Any, plugins: Any, outputs: Any, **params: Any) -> Demo: ...

    def status_lines(self, snapshot: dict[str, Any]) -> list[str]: ...


# --------------------------------------------------------------------------- studies
@runtime_checkable
class SimulatedObserver(Protocol):
    """A simulated participant answering a study's trials. ``haptable study run
    --simulate`` asks the first one registered.

    ``respond(trial, played, *, participant_seed) -> (response, response_time_s)``: the
    answer to one trial of a plan (the ``plan.json`` trial: ``direction``, ``pair`` or
    ``region``, ``hand``, ``stimulus``) after the stimulus ``played`` (the ``OutputPlan``
    the outputs accepted); the same seed and trial give the same answer.
    ``parameters(participant_seed) -> dict``: the participant's observer parameters (JSON
    values, stored in ``participant.json``)."""

    def respond(
        self, trial: Mapping[str, Any], played: OutputPlan, *, participant_seed: int
    ) -> tuple[str, float]: ...

    def parameters(self, participant_seed: int) -> dict[str, Any]: ...


@runtime_checkable
class KnobTrials(Effect, Protocol):
    """The knob task, one trial: ``knob_trial(condition=, sectors=, distance_deg=,
    seed=)`` with a simulated finger, ``knob_live_trial(..., outputs=, attach=,
    max_time_s=)`` with a person (the knob session streams through ``outputs``;
    ``attach(session)`` feeds it the camera's contacts, ``session.feed(t_capture_s,
    contacts)``, and ``attach(None)`` ends that). Both return a dict with ``start_item``,
    ``target_item``, ``completion_time_s``, ``overshoots``, ``recovery_time_s`` (None
    when it timed out), ``timed_out``, ``crossings``, ``detents`` and ``error``.
    ``session(condition, sectors)``: a live knob session (the knob demo drives it)."""

    def session(self, condition: str = "HD+VF", sectors: int | None = None) -> Any: ...

    def knob_trial(
        self, *, condition: str, sectors: int, distance_deg: float, seed: int
    ) -> dict[str, Any]: ...

    def knob_live_trial(
        self,
        *,
        condition: str,
        sectors: int,
        distance_deg: float,
        outputs: Any,
        attach: Callable[[Any], None],
        max_time_s: float = 30.0,
    ) -> dict[str, Any]: ...


# --------------------------------------------------------------------------- others
@runtime_checkable
class Vibrometer(Protocol):
    """A vibration-map measurement device: ``measure(progress=None) -> dict`` whose items
    are the arguments of ``console.files.vibration_map.make_map`` plus ``meta``;
    ``progress(done, total)`` may raise (an operator's cancel) to stop it."""

    def measure(self, progress: Callable[[int, int], None] | None = None) -> dict[str, Any]: ...


#: The contract of what each kind's factory builds (``plugins.Plugins.build`` checks it).
KIND_CONTRACTS: dict[str, type] = {
    "camera": Camera,
    "classifier": Classifier,
    "effect": Effect,
    "audio_output": AudioOutput,
    "relay_board": RelayBoard,
    "vibrometer": Vibrometer,
    "scene": Scene,
    "projector": ProjectorLauncher,
    "demo": Demo,
    "frame_sink": FrameSink,
    "panel": Panel,
    "observer": SimulatedObserver,
    "recording_reader": RecordingReader,
}

#: The contract of the factory itself, for kinds whose factory is not ``f(profile)``.
FACTORY_CONTRACTS: dict[str, type] = {
    "projector": ProjectorFactory,
    "demo": DemoFactory,
    "frame_sink": FrameSinkFactory,
    "panel": PanelFactory,
}
