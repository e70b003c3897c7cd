"""The safety gate's parts that hold no rule: its events, its changing state (written
by the gate's own methods only) and the read-only view of its scope."""

from __future__ import annotations

import threading
from collections import deque
from collections.abc import Callable
from dataclasses import dataclass
from typing import Any, NoReturn

import numpy as np

from console.safety.scope import ScopeTap, ScopeTrace
from console.safety.sources import Source


@dataclass(frozen=True)
class GateEvent:
    t_s: float
    clock: int
    kind: str  # "estop", "shutdown", "refused", "switch", "fault", "reset"
    message: str
    #: an e-stop a driver may answer by dropping its queued blocks at once (an operator's),
    #: and then every block until the gate hands one ending in silence (the rest of its
    #: ramp down, played after the drop, would step up from 0 V); a fault's e-stop is not
    #: cut: the gate's ramp to zero at the slew limit plays out
    cut: bool = True
    #: on "estop", "shutdown" and "fault": the step (volts per sample, one per sound-card
    #: channel) the gate ramps down with at that moment, for a driver ramping on its own
    ramp_step_v: tuple[float, ...] = ()


class GateState:
    """The gate's changing state. Only the gate's own methods write it."""

    __slots__ = (
        "audio_thread",
        "clock",
        "estop_reason",
        "estopped",
        "events",
        "in_fill",
        "last_nonzero",
        "last_switch",
        "latency_fixed",
        "latency_samples",
        "level_v",
        "listeners",
        "quiet_until",
        "relays",
        "source",
        "steps_for",
        "switching",
    )

    def __init__(self, n_channels: int, relays: tuple[bool, ...], latency_samples: int) -> None:
        self.source: Source | None = None
        self.estopped = False
        self.estop_reason = ""
        self.switching = False
        self.clock = 0  # samples handed to the driver
        self.last_nonzero = -(10**12)
        self.quiet_until = 0  # no signal before this clock (post-switch settle)
        self.last_switch: dict[int, int] = {}  # channel -> clock of its last switch
        #: (relays, connected patches, read-only steps) for the last relay state looked up
        self.steps_for: tuple[tuple[bool, ...], frozenset[str], np.ndarray] | None = None
        #: last sample handed out per channel, volts at the actuators
        self.level_v: tuple[float, ...] = (0.0,) * n_channels
        self.relays = relays
        self.events: deque[GateEvent] = deque(maxlen=1000)
        self.audio_thread: threading.Thread | None = None
        #: the driver is inside ``fill`` (waiting on the gate: it has not stopped pulling)
        self.in_fill = False
        self.listeners: tuple[Callable[[GateEvent], None], ...] = ()
        self.latency_samples = latency_samples
        self.latency_fixed = False  # ``set_device_latency`` was called


class ScopeView:
    """Read-only access to the gate's scope tap: only the gate writes to it."""

    __slots__ = ("_tap",)

    def __init__(self, tap: ScopeTap) -> None:
        object.__setattr__(self, "_tap", tap)

    def __setattr__(self, name: str, value: Any) -> NoReturn:
        raise AttributeError(f"the gate's scope is read-only: {name!r} cannot be set")

    def __delattr__(self, name: str) -> NoReturn:
        raise AttributeError(f"the gate's scope is read-only: {name!r} cannot be deleted")

    @property
    def sample_rate_hz(self) -> int:
        return self._tap.sample_rate_hz

    @property
    def channels(self) -> tuple[str, ...]:
        return self._tap.channels

    @property
    def capacity(self) -> int:
        return self._tap.capacity

    def read(self, seconds: float | None = None) -> ScopeTrace:
        """The newest ``seconds`` (all kept when None) in volts at the actuators."""
        return self._tap.read(seconds)
