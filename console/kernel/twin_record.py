"""What the twin's amplifiers and relays got, as a client keeps it when its outputs close
(the twin's logs): ``TwinRecord`` and its relay switches, ``SwitchRecord``."""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from console.safety import GateEvent


@dataclass(frozen=True)
class SwitchRecord:
    """A relay switch of the twin's board: when, which, and the level at the amplifiers."""

    t_s: float
    clock: int
    channel: int
    closed: bool
    level_v: tuple[float, ...]


@dataclass(frozen=True)
class TwinRecord:
    """What the twin's amplifiers and relays got, kept when outputs close (twin logs)."""

    recording_v: np.ndarray | None
    relay_log: list[SwitchRecord] | None
    events: list[GateEvent]
    estop_reason: str
    latency_samples: int
    #: the twin DAC's underruns: (clock the gap fell before, its length in samples)
    underruns: tuple[tuple[int, int], ...] = ()
