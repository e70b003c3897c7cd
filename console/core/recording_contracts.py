"""The capability of reading recorded runs back (``plugins/recording``'s frame-sink
factory offers it): the console's Camera and Scope screens show a recording through it,
never through the recording plugin's modules. Re-exported by ``console.core.contracts``."""

from __future__ import annotations

from typing import Any, Protocol, runtime_checkable

from console.core.sink_contracts import FrameSinkFactory


@runtime_checkable
class RecordedRun(Protocol):
    """An open recording: ``n_frames`` frames, each ``frame(k)`` (H, W) uint8 with its
    number ``seq[k]`` and capture time ``t_capture_s[k]`` (s), ``decisions(k)`` (JSON
    values: ``contacts`` ``[id, pos_px, pos_mm, area_px]``, ``hands`` with ``center_px``,
    ``radius_px``, ``finger_count``, ``gesture`` ``[name, kind, confidence]``, a
    ``plan`` record ...), ``plans()`` (what the run handed its outputs, JSON lines with
    ``kind``; a plan's ``name``, ``hash``, ``duration_s``, ``segments``, ``meta`` and
    the kernel's clocks: not its samples, re-rendered from ``meta`` where shown),
    ``gate_events()`` (the kernel's own events: ``t_s``, ``clock``, ``kind``, ``message``;
    ``console.core.gate_log``), ``close()``. A run that keeps the vibration map its
    plans were rendered on offers ``KeepsItsMap`` too."""

    path: Any
    n_frames: int
    seq: Any
    t_capture_s: Any

    def frame(self, k: int) -> Any: ...

    def decisions(self, k: int) -> dict: ...

    def plans(self) -> list[dict]: ...

    def gate_events(self) -> list[dict]: ...

    def close(self) -> None: ...


@runtime_checkable
class KeepsItsMap(Protocol):
    """A recorded run that keeps the vibration map its plans were rendered on (a
    study's trial): ``vibration_map()`` (None when it is missing); the Scope re-renders
    its plans on it."""

    def vibration_map(self) -> Any: ...


@runtime_checkable
class ReadsRecordings(FrameSinkFactory, Protocol):
    """A frame-sink factory that also reads what its sinks wrote:
    ``open_recording(path) -> RecordedRun``; a bad file is one ``UserError`` line naming
    it (a ``console.core.words.Placed``: its fix worded for the console too)."""

    def open_recording(self, path: str) -> RecordedRun: ...


@runtime_checkable
class RecordingReader(Protocol):
    """A reader of recorded runs in a format of its own (kind ``recording_reader``):
    ``reads(path)`` says whether the file is one (cheap, never raises),
    ``open_recording(path) -> RecordedRun`` opens it (one ``UserError`` line otherwise)."""

    def reads(self, path: str) -> bool: ...

    def open_recording(self, path: str) -> RecordedRun: ...


@runtime_checkable
class WatchesOutputs(Protocol):
    """A frame sink that sees what a demo hands its outputs: ``watch_outputs(outputs)``
    returns the outputs the demo uses instead (every call passed on, as
    ``console.core.plan_watch.WatchedOutputs`` does)."""

    def watch_outputs(self, outputs: Any) -> Any: ...


@runtime_checkable
class BeginsRun(Protocol):
    """A frame sink that keeps what a demo starts from: ``begin(demo=, classifier=,
    scene=)`` before the first frame."""

    def begin(self, *, demo: str = "", classifier: Any = None, scene: Any = None) -> None: ...
