"""The plugin API, runtime part: what a plugin may import from the console's runtime,
its outputs client and its session (see ``console.plugin_api`` for the whole API).

Each name is loaded on first use (a module ``__getattr__``), so ``from
console.plugin_api.runtime import MAX_SOCKET_PATH`` costs what importing the projector
protocol costs, not the whole runtime (scipy and all): a plugin's settings can name a
runtime value at registration time without making the console start slower. Each source
module is imported by a plain ``from ... import`` in ``_source`` below, so the import
graph and layer tests see every edge.

What it offers, by where it comes from:

- frame loop and stages: ``FrameLoop``, ``PASSED`` (a stage that did nothing this frame),
  ``VisionStage``, ``learn_background``,
  ``open_camera``, ``open_classifier``, ``vision_loop``, ``Watchdog``
- latency and timing: ``LatencyMonitor``, ``DEQUEUED``, ``PROCESSING``; jitter probes
  ``start_probe``, ``start_probe_beside``, ``finish_probe``
- tracking: ``Tracking``, ``TrackFrame``, ``Announcer``
- the measured vibration map: ``measured_map``, ``measured_map_file``, ``Cancelled``,
  ``kept_measured_map`` (the kept one only, never measuring); a study run's hold on it
  across processes ``map_held``, ``map_holder``; a run's hold on the table's outputs
  ``table_held``, ``table_holder``
- the projector link: ``ProjectorService``, ``ProjectorLaunch``, the wire protocol as
  ``projector_protocol`` and its names ``encode``, ``MessageReader``, ``ProtocolError``,
  ``probe``, ``default_socket_path``, ``socket_path_for``, ``prepare_socket_dir``,
  ``HEARTBEAT_S``, ``PEER_TIMEOUT_S``, ``MAX_SOCKET_PATH``, ``TO_PROJECTOR``
- the outputs (the table's safety kernel): ``open_outputs``; duplex inputs ``capture``
  (play a plan, get what the inputs read), ``read_inputs``, ``move_sensor`` and
  ``inject_twin_faults`` (the twin's),
  ``Capture``; private runtime files
  ``runtime_dir``, ``ensure_private_dir``, ``write_private``
- session events: ``Started``, ``Progress``, ``Snapshot``, ``Stopped``, ``Failed``
"""

from __future__ import annotations

from types import ModuleType
from typing import TYPE_CHECKING, Any

if TYPE_CHECKING:  # the same names, for type checkers (loaded lazily below)
    from console.kernel.capture import (
        Capture,
        capture,
        inject_twin_faults,
        move_sensor,
        read_inputs,
    )
    from console.kernel.client import open_outputs
    from console.kernel.private_dir import ensure_private_dir, runtime_dir, write_private
    from console.runtime.jitter import finish_probe, start_probe, start_probe_beside
    from console.runtime.latency import DEQUEUED, PROCESSING, LatencyMonitor
    from console.runtime.loop import PASSED, FrameLoop
    from console.runtime.map_hold import map_held, map_holder
    from console.runtime.measured_map import (
        Cancelled,
        kept_measured_map,
        measured_map,
        measured_map_file,
    )
    from console.runtime.projector import protocol as projector_protocol
    from console.runtime.projector.protocol import (
        HEARTBEAT_S,
        MAX_SOCKET_PATH,
        PEER_TIMEOUT_S,
        TO_PROJECTOR,
        MessageReader,
        ProtocolError,
        default_socket_path,
        encode,
        prepare_socket_dir,
        probe,
        socket_path_for,
    )
    from console.runtime.projector.service import ProjectorService
    from console.runtime.projector.supervisor import ProjectorLaunch
    from console.runtime.stages import (
        VisionStage,
        learn_background,
        open_camera,
        open_classifier,
        vision_loop,
    )
    from console.runtime.table_hold import table_held, table_holder
    from console.runtime.tracking import Announcer, TrackFrame, Tracking
    from console.runtime.watchdog import Watchdog
    from console.session.events import (
        ESTOP_FIX,
        ESTOP_REFUSAL,
        Failed,
        Progress,
        Snapshot,
        Started,
        Stopped,
    )

#: source module (short name) -> the names it gives the API
_NAMES: dict[str, tuple[str, ...]] = {
    "loop": ("FrameLoop", "PASSED"),
    "stages": ("VisionStage", "learn_background", "open_camera", "open_classifier", "vision_loop"),
    "watchdog": ("Watchdog",),
    "latency": ("DEQUEUED", "PROCESSING", "LatencyMonitor"),
    "jitter": ("finish_probe", "start_probe", "start_probe_beside"),
    "tracking": ("Announcer", "TrackFrame", "Tracking"),
    "measured_map": ("Cancelled", "kept_measured_map", "measured_map", "measured_map_file"),
    "map_hold": ("map_held", "map_holder"),
    "table_hold": ("table_held", "table_holder"),
    "protocol": (
        "HEARTBEAT_S",
        "MAX_SOCKET_PATH",
        "PEER_TIMEOUT_S",
        "TO_PROJECTOR",
        "MessageReader",
        "ProtocolError",
        "default_socket_path",
        "encode",
        "prepare_socket_dir",
        "probe",
        "socket_path_for",
    ),
    "service": ("ProjectorService",),
    "supervisor": ("ProjectorLaunch",),
    "client": ("open_outputs",),
    "capture": ("Capture", "capture", "inject_twin_faults", "move_sensor", "read_inputs"),
    "private_dir": ("ensure_private_dir", "runtime_dir", "write_private"),
    "events": (
        "ESTOP_FIX",
        "ESTOP_REFUSAL",
        "Failed",
        "Progress",
        "Snapshot",
        "Started",
        "Stopped",
    ),
}
_SOURCE_OF = {name: source for source, names in _NAMES.items() for name in names}

__all__ = [
    "projector_protocol",
    "Announcer",
    "Cancelled",
    "Capture",
    "capture",
    "default_socket_path",
    "DEQUEUED",
    "encode",
    "ensure_private_dir",
    "ESTOP_FIX",
    "ESTOP_REFUSAL",
    "Failed",
    "finish_probe",
    "FrameLoop",
    "PASSED",
    "HEARTBEAT_S",
    "LatencyMonitor",
    "learn_background",
    "MAX_SOCKET_PATH",
    "kept_measured_map",
    "measured_map",
    "map_held",
    "map_holder",
    "table_held",
    "table_holder",
    "measured_map_file",
    "MessageReader",
    "inject_twin_faults",
    "move_sensor",
    "open_camera",
    "open_classifier",
    "open_outputs",
    "PEER_TIMEOUT_S",
    "prepare_socket_dir",
    "probe",
    "PROCESSING",
    "Progress",
    "ProjectorLaunch",
    "read_inputs",
    "ProjectorService",
    "ProtocolError",
    "runtime_dir",
    "Snapshot",
    "socket_path_for",
    "start_probe",
    "start_probe_beside",
    "Started",
    "Stopped",
    "TO_PROJECTOR",
    "TrackFrame",
    "Tracking",
    "vision_loop",
    "VisionStage",
    "Watchdog",
    "write_private",
]


def _source(source: str) -> ModuleType:
    """The module behind a short source name, imported now (first use)."""
    if source == "loop":
        from console.runtime import loop as module  # lazy: loads on first use
    elif source == "stages":
        from console.runtime import stages as module  # lazy: loads on first use
    elif source == "watchdog":
        from console.runtime import watchdog as module  # lazy: loads on first use
    elif source == "latency":
        from console.runtime import latency as module  # lazy: loads on first use
    elif source == "jitter":
        from console.runtime import jitter as module  # lazy: loads on first use
    elif source == "tracking":
        from console.runtime import tracking as module  # lazy: loads on first use
    elif source == "measured_map":
        from console.runtime import measured_map as module  # lazy: loads on first use
    elif source == "map_hold":
        from console.runtime import map_hold as module  # lazy: loads on first use
    elif source == "table_hold":
        from console.runtime import table_hold as module  # lazy: loads on first use
    elif source == "protocol":
        from console.runtime.projector import protocol as module  # lazy: loads on first use
    elif source == "service":
        from console.runtime.projector import service as module  # lazy: loads on first use
    elif source == "supervisor":
        from console.runtime.projector import supervisor as module  # lazy: loads on first use
    elif source == "client":
        from console.kernel import client as module  # lazy: loads on first use
    elif source == "capture":
        from console.kernel import capture as module  # lazy: loads on first use
    elif source == "private_dir":
        from console.kernel import private_dir as module  # lazy: loads on first use
    elif source == "events":
        from console.session import events as module  # lazy: loads on first use
    else:  # pragma: no cover - _NAMES and this list are kept together
        raise KeyError(source)
    return module


def __getattr__(name: str) -> Any:
    """Load ``name`` from its runtime module on first use, then keep it here."""
    if name == "projector_protocol":
        value: Any = _source("protocol")
    elif name in _SOURCE_OF:
        value = vars(_source(_SOURCE_OF[name]))[name]  # listed in _NAMES: always there
    else:
        raise AttributeError(f"module {__name__!r} has no attribute {name!r}")
    globals()[name] = value
    return value


def __dir__() -> list[str]:
    return sorted({*globals(), *__all__})
