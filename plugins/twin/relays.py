"""The twin relay board and the wire it shares with the twin amplifiers.

The board has the MaxiCoupler's channels and logs every switch with the output level at
that moment (the level the twin DAC puts out then, a gap's hold or ramp included, as the
real contacts would see it) and the clock of that sample (an index into the recording).
The wire (``bus_for(profile)``) is how the relays learn that level: the live twin audio
output of the profile drives it.
"""

from __future__ import annotations

import time
from collections.abc import Callable
from dataclasses import dataclass, field
from typing import Any


@dataclass
class _Bus:
    """The wire between the twin amplifiers' output and the twin relays.

    The live twin audio output that started last drives it (one live set of outputs per
    profile, as on the real table): its probe gives the clock of the sample at the
    amplifiers now (samples played since that output started) and its level in volts.
    When it stops, the output that was driving before it (still live) drives again: two
    outputs of one profile file (a profile changed in memory keeps its path) never leave
    a stopped output's clock on the other's relay log.
    """

    level_v: tuple[float, ...] = (0.0, 0.0)
    clock: int = 0
    probes: list[Callable[[], tuple[int, tuple[float, ...]]]] = field(default_factory=list)
    board: Any = None  # the twin relay board on this wire (its log: the twin's inputs)

    def now(self) -> tuple[int, tuple[float, ...]]:
        probes = self.probes
        return probes[-1]() if probes else (self.clock, self.level_v)

    def drive(self, probe: Callable[[], tuple[int, tuple[float, ...]]]) -> None:
        """``probe``'s output drives the wire from now on."""
        self.release(probe)
        self.clock = 0
        self.probes.append(probe)

    def release(self, probe: Callable[[], tuple[int, tuple[float, ...]]]) -> None:
        """``probe``'s output stopped: the one before it drives again (its last clock and
        level stay on the wire when no output is left)."""
        if probe in self.probes:
            if self.probes[-1] == probe:
                self.clock, self.level_v = probe()
            self.probes.remove(probe)


_BUSES: dict[str, _Bus] = {}


def bus_for(profile) -> _Bus:
    return _BUSES.setdefault(str(profile.path), _Bus())


@dataclass(frozen=True)
class SwitchRecord:
    t_s: float
    clock: int
    channel: int
    closed: bool
    level_v: tuple[float, ...]  # every output channel's volts at the switch


class TwinRelayBoard:
    """An 8-channel solid-state relay board like the Yocto-MaxiCoupler."""

    def __init__(self, profile):
        self.channels = int(profile.get("relays.channels"))
        self.switch_time_s = profile.get("relays.switch_time_ms") * 1e-3
        self._state = [False] * self.channels
        self._bus = bus_for(profile)
        self._bus.board = self
        self.log: list[SwitchRecord] = []
        self.fail_on: set[int] = set()  # fault injection: channels whose command fails

    def set(self, channel: int, closed: bool) -> None:
        if not 1 <= channel <= self.channels:
            raise ValueError(f"relay channel {channel} out of 1..{self.channels}")
        if channel in self.fail_on:
            raise OSError(f"twin relay {channel} did not respond")
        if self._state[channel - 1] != closed:
            self._state[channel - 1] = closed
            clock, level_v = self._bus.now()
            self.log.append(SwitchRecord(time.monotonic(), clock, channel, closed, level_v))

    def states(self) -> tuple[bool, ...]:
        return tuple(self._state)

    def close(self) -> None:
        for ch in range(1, self.channels + 1):
            if ch not in self.fail_on:
                self.set(ch, False)

    def status(self) -> dict[str, Any]:
        return {
            "driver": "twin",
            "channels": self.channels,
            "closed": [i + 1 for i, s in enumerate(self._state) if s],
            "switches": len(self.log),
        }
