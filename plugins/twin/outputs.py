"""Twin audio output and relay board: the table's outputs simulated and recorded.

The audio output pulls blocks from the safety gate paced in real time (or as fast as
possible for tests) and records exactly what it was given. The relay board has the
MaxiCoupler's channels and logs every switch with the output level at that moment
(read from the twin audio output it is wired to, as the real contacts would see it).
"""

from __future__ import annotations

import threading
import time
from collections import deque
from dataclasses import dataclass
from typing import Any

import numpy as np

from console.types import BlockSource


@dataclass
class _Bus:
    """The wire between the twin amplifiers' output and the twin relays.

    The twin audio output that started last drives it (one live set of outputs per
    profile, as on the real table); its clock counts the samples that output played.
    """

    level_v: tuple[float, float] = (0.0, 0.0)
    clock: int = 0


_BUSES: dict[str, _Bus] = {}


def bus_for(profile) -> _Bus:
    return _BUSES.setdefault(str(profile.path), _Bus())


class TwinAudioOutput:
    """Two channels (left piezo, right screen) into the simulated amplifiers."""

    def __init__(self, profile, *, record_s: float = 120.0):
        self.sample_rate_hz = int(profile.get("audio.sample_rate_hz"))
        self.block_size = int(profile.get("audio.block_size"))
        self.paced = bool(profile.get("audio.paced"))
        full = float(profile.get("audio.full_scale_v"))
        self._to_v = np.array(
            [
                full * profile.get("amplifiers.piezo_gain"),
                full * profile.get("amplifiers.screen_gain"),
            ],
            dtype=np.float32,
        )
        self._bus = bus_for(profile)
        self._blocks: deque[np.ndarray] = deque(
            maxlen=max(1, int(record_s * self.sample_rate_hz / self.block_size))
        )
        self._thread: threading.Thread | None = None
        self._stop = threading.Event()
        self.underruns = 0
        self.blocks = 0
        self.callback_s: deque[float] = deque(maxlen=4096)
        self._source: BlockSource | None = None

    # AudioOutput protocol
    def start(self, source: BlockSource) -> None:
        if self._thread is not None:
            return
        self._source = source
        self._bus.clock = 0  # this output drives the wire from now on
        self._bus.level_v = (0.0, 0.0)
        self._stop.clear()
        self._thread = threading.Thread(target=self._run, name="haptable-twin-audio", daemon=True)
        self._thread.start()

    def stop(self) -> None:
        self._stop.set()
        if self._thread is not None and self._thread is not threading.current_thread():
            self._thread.join(timeout=2.0)
        self._thread = None

    def status(self) -> dict[str, Any]:
        return {
            "driver": "twin",
            "running": self._thread is not None,
            "paced": self.paced,
            "sample_rate_hz": self.sample_rate_hz,
            "block_size": self.block_size,
            "latency_s": self.block_size / self.sample_rate_hz,
            "underruns": self.underruns,
            "blocks": self.blocks,
        }

    def _run(self) -> None:
        out = np.zeros((self.block_size, 2), dtype=np.float32)
        period = self.block_size / self.sample_rate_hz
        t_next = time.monotonic()
        src = self._source
        while not self._stop.is_set():
            if not self.paced and src.idle:
                time.sleep(0.0002)  # fast-forward: the clock only runs while there is work
                continue
            t0 = time.perf_counter()
            src.fill(out)
            self.callback_s.append(time.perf_counter() - t0)
            self._blocks.append(out.copy())
            self.blocks += 1
            last = out[-1] * self._to_v
            self._bus.level_v = (float(last[0]), float(last[1]))
            self._bus.clock += self.block_size
            if self.paced:
                t_next += period
                delay = t_next - time.monotonic()
                if delay > 0:
                    time.sleep(delay)
                elif delay < -period:  # a whole block late: the device would have starved
                    self.underruns += 1
                    t_next = time.monotonic()
            else:
                time.sleep(0)  # let feeders (camera, knob) run: a fast-forward loop starves them

    # twin extras
    def recording_card(self) -> np.ndarray:
        """Everything played, (n, 2) in sound-card units."""
        blocks = list(self._blocks)
        return np.concatenate(blocks) if blocks else np.zeros((0, 2), np.float32)

    def recording_v(self) -> np.ndarray:
        """Everything played, (n, 2) in volts at the piezo patches / screen."""
        return self.recording_card().astype(np.float64) * self._to_v

    def clear_recording(self) -> None:
        self._blocks.clear()


@dataclass(frozen=True)
class SwitchRecord:
    t_s: float
    clock: int
    channel: int
    closed: bool
    level_v: tuple[float, float]


class TwinRelayBoard:
    """An 8-channel solid-state relay board like the Yocto-MaxiCoupler."""

    def __init__(self, profile):
        self.channels = int(profile.get("relays.channels"))
        self.switch_time_s = profile.get("relays.switch_time_ms") * 1e-3
        self._state = [False] * self.channels
        self._bus = bus_for(profile)
        self.log: list[SwitchRecord] = []
        self.fail_on: set[int] = set()  # fault injection: channels whose command fails

    def set(self, channel: int, closed: bool) -> None:
        if not 1 <= channel <= self.channels:
            raise ValueError(f"relay channel {channel} out of 1..{self.channels}")
        if channel in self.fail_on:
            raise OSError(f"twin relay {channel} did not respond")
        if self._state[channel - 1] != closed:
            self._state[channel - 1] = closed
            self.log.append(
                SwitchRecord(time.monotonic(), self._bus.clock, channel, closed, self._bus.level_v)
            )

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
