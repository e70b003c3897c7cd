"""Twin audio output and relay board: the table's outputs simulated and recorded.

The audio output pulls blocks from the safety gate and records exactly what it was
given. Paced (real time), it behaves like a sound card with a device buffer of
``[twin_audio] buffer_periods`` blocks: its thread fills the buffer ahead while the
simulated DAC plays it at the sample rate, and an underrun is counted only when the DAC
finds the buffer empty (the thread was more than ``buffer_periods - 1`` blocks late, as
on ALSA/PortAudio). The buffer adds ``buffer_periods`` blocks of output latency, reported
in ``status()["latency_s"]`` (the safety gate adds it to its guard and settle gaps). An
operator's e-stop (a ``cut`` event) drops the queued blocks (like the sounddevice driver's
``abort``): the output is silent from the sample playing when the gate's e-stop event
fires, and stays silent until the gate's own ramp down is over (the block under way at
the event and every later one are dropped until the gate hands a block that ends in
silence). Playing the rest of the gate's ramp after the drop would step the amplifiers
from 0 V back up to the ramp's level: a step over the slew limit the gate never made.
Fast-forward (not paced) it has no buffer: a block counts as played when handed over.

The relay board has the MaxiCoupler's channels and logs every switch with the output
level at that moment (the sample the twin DAC is playing then, as the real contacts would
see it) and the clock of that sample (an index into the recording).
"""

from __future__ import annotations

import math
import sys
import threading
import time
from collections import deque
from collections.abc import Callable
from dataclasses import dataclass, field
from typing import Any

import numpy as np

from console.channels import ChannelLayout
from console.contracts import BlockSource
from console.realtime import realtime_priority

#: Device buffer of the paced twin, in blocks (a real card's driver fills 2-4 periods ahead).
DEFAULT_BUFFER_PERIODS = 3
#: Seconds of audio the twin keeps for ``recording_v`` (a bounded ring).
DEFAULT_RECORD_S = 120.0


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


def _key(profile, dotted: str, default):
    try:
        v = profile.get(dotted)
    except Exception:  # a bare profile stub without the section
        v = None
    return default if v is None else v


class TwinAudioOutput:
    """The profile's ``[audio] channels`` (by default two: left piezo, right screen) into
    the simulated amplifiers, one amplifier per channel."""

    def __init__(
        self,
        profile,
        *,
        record_s: float | None = None,
        buffer_periods: int | None = None,
    ):
        self.sample_rate_hz = int(profile.get("audio.sample_rate_hz"))
        self.block_size = int(profile.get("audio.block_size"))
        self.paced = bool(profile.get("audio.paced"))
        if buffer_periods is None:
            buffer_periods = _key(profile, "twin_audio.buffer_periods", DEFAULT_BUFFER_PERIODS)
        self.buffer_periods = max(2, int(buffer_periods))  # 1: no slack at all
        if record_s is None:
            record_s = float(_key(profile, "twin_audio.record_s", DEFAULT_RECORD_S))
        full = float(profile.get("audio.full_scale_v"))
        gain = {
            "piezo": full * profile.get("amplifiers.piezo_gain"),
            "screen": full * profile.get("amplifiers.screen_gain"),
        }
        self.channels = ChannelLayout.from_profile(profile).names
        kinds = ChannelLayout(self.channels).kinds()
        self._to_v = np.array([gain[k] for k in kinds], dtype=np.float32)
        n_ch = len(self.channels)
        self._bus = bus_for(profile)
        bs = self.block_size
        self._cap = bs * max(1, math.ceil(record_s * self.sample_rate_hz / bs))
        self._rec = np.empty((self._cap, n_ch), dtype=np.float32)  # ring, indexed by clock
        # written here, not first in the audio thread: touching fresh pages there (each
        # new 2 MB huge page zeroed on demand) stalled it 5-7 ms every ~5 s: underruns
        self._rec.fill(0.0)
        self._lock = threading.Lock()
        self._written = 0  # samples handed over by the gate (= the recording's clock)
        self._kept_from = 0  # oldest clock still in the ring
        self._t0: float | None = None  # DAC clock: sample _s0 played at _t0 (None: priming)
        self._s0 = 0
        # an operator's e-stop cut the output: blocks are dropped until the gate's ramp
        # down is over (until it hands a block that ends in silence)
        self._cutting = False
        self._filling = False  # the driver is inside the gate's fill (a block under way)
        self._handed_silent = True  # the last block the gate handed ended at 0 V everywhere
        self._thread: threading.Thread | None = None
        self._stop = threading.Event()
        self.realtime_priority = False
        self.underruns = 0
        self.underrun_s = 0.0  # silence the DAC played while the buffer was empty
        self.underruns_audible = 0  # ... of them, cutting into output (the last block not silent)
        self._last_block_sounded = False
        self.blocks = 0
        self.callback_s: deque[float] = deque(maxlen=4096)
        self._source: BlockSource | None = None
        self._out = np.zeros((self.block_size, n_ch), dtype=np.float32)

    # AudioOutput protocol
    def start(self, source: BlockSource) -> None:
        if self._thread is not None:
            return
        self._source = source
        with self._lock:
            self._t0, self._s0 = None, self._written
        self._bus.level_v = (0.0,) * len(self.channels)
        self._bus.drive(self._probe)  # this output drives the wire from now on
        listeners = getattr(source, "listeners", None)
        if isinstance(listeners, list):
            listeners.append(self._on_gate_event)
        self._stop.clear()
        self._thread = threading.Thread(target=self._run, name="haptable-twin-audio", daemon=True)
        self._thread.start()

    def stop(self) -> None:
        self._stop.set()
        if self._thread is not None and self._thread is not threading.current_thread():
            self._thread.join(timeout=2.0)
        self._thread = None
        with self._lock:  # the DAC plays out what was queued
            self._t0 = None
            self._s0 = self._written
        listeners = getattr(self._source, "listeners", None)
        if isinstance(listeners, list) and self._on_gate_event in listeners:
            listeners.remove(self._on_gate_event)
        self._bus.release(self._probe)

    @property
    def latency_s(self) -> float:
        """Handing a sample over -> it has been played (at most): the device buffer."""
        periods = self.buffer_periods if self.paced else 1
        return periods * self.block_size / self.sample_rate_hz

    def status(self) -> dict[str, Any]:
        return {
            "driver": "twin",
            "running": self._thread is not None,
            "paced": self.paced,
            "sample_rate_hz": self.sample_rate_hz,
            "block_size": self.block_size,
            "buffer_periods": self.buffer_periods if self.paced else 1,
            "latency_s": self.latency_s,
            "realtime_priority": self.realtime_priority,
            "underruns": self.underruns,
            "underrun_s": round(self.underrun_s, 4),
            "underruns_audible": self.underruns_audible,
            "blocks": self.blocks,
        }

    # the simulated DAC ---------------------------------------------------------------
    def _played(self, now: float) -> int:
        """Clock of the sample the DAC plays at ``now`` (caller holds the lock)."""
        if not self.paced:
            return self._written
        if self._t0 is None:
            return self._s0
        return min(self._written, self._s0 + int((now - self._t0) * self.sample_rate_hz + 1e-6))

    def _probe(self) -> tuple[int, tuple[float, ...]]:
        with self._lock:
            p = self._played(time.monotonic())
            if p <= self._kept_from or p == 0:
                lvl = (0.0,) * len(self.channels)
            else:
                x = self._rec[(p - 1) % self._cap] * self._to_v
                lvl = tuple(float(v) for v in x)
        return p, lvl

    def _on_gate_event(self, ev: Any) -> None:
        """E-stop: drop the queued blocks (silent from the sample playing now), and every
        block the gate hands until its ramp down is over."""
        if getattr(ev, "kind", "") not in ("estop", "shutdown") or not getattr(ev, "cut", True):
            return  # a fault's e-stop: the gate's ramp to zero plays out
        t = getattr(ev, "t_s", None) or time.monotonic()  # the moment of the e-stop
        with self._lock:
            self._silence(self._played(t), self._written)
            # a block under way now may have been filled before the gate saw its e-stop
            # (signal), and every later one is the gate's ramp from the level it last
            # handed: dropped too, unless the gate was silent and nothing is under way.
            # (A fill that starts after this reads the e-stop: it ramps from that level.)
            self._cutting = self._cutting or self._filling or not self._handed_silent

    def _silence(self, a: int, b: int) -> None:
        """Zero clocks ``a..b`` of the ring (caller holds the lock)."""
        a = max(a, self._kept_from, b - self._cap)
        if b <= a:
            return
        i, j = a % self._cap, b % self._cap
        if i < j:
            self._rec[i:j] = 0.0
        else:
            self._rec[i:] = 0.0
            self._rec[:j] = 0.0

    def _store(self, out: np.ndarray) -> None:
        """Queue a filled block (caller holds the lock)."""
        n = out.shape[0]
        i = self._written % self._cap
        cut = self._cutting
        self._rec[i : i + n] = 0.0 if cut else out
        self._last_block_sounded = not cut and bool(out.any())
        self._handed_silent = not out[-1].any()
        if self._handed_silent:  # the gate's ramp down is over: nothing left to drop
            self._cutting = False
        self._filling = False
        self._written += n
        self._kept_from = max(self._kept_from, self._written - self._cap)
        self.blocks += 1

    def _fill(self, src: BlockSource, out: np.ndarray) -> None:
        # set before the gate is called (an e-stop event that read False came before this
        # fill, which then reads the gate's e-stop flag and ramps from the level last handed)
        self._filling = True
        t0 = time.perf_counter()
        src.fill(out)
        self.callback_s.append(time.perf_counter() - t0)

    def _run(self) -> None:
        src = self._source
        if self.paced:
            self.realtime_priority = realtime_priority()
            # the driver thread needs the GIL within its slack ((buffer_periods - 1) blocks):
            # Python hands it over only every switch interval (5 ms by default)
            slack_s = (self.buffer_periods - 1) * self.block_size / self.sample_rate_hz
            if sys.getswitchinterval() > slack_s / 2:
                sys.setswitchinterval(slack_s / 2)
        while not self._stop.is_set():
            if not self.paced:
                if src.idle:
                    time.sleep(0.0002)  # fast-forward: the clock only runs while there is work
                    continue
                self.step(time.monotonic())
                time.sleep(0)  # let feeders (camera, knob) run: a fast-forward loop starves them
                continue
            wait_s = self.step(time.monotonic())
            if wait_s > 0:
                time.sleep(wait_s)

    def step(self, now: float) -> float:
        """The driver thread's work at time ``now``: fill one block if the device buffer
        has room (returns 0), else the seconds until the DAC frees a block. Counts an
        underrun when the DAC found the buffer empty (the thread came too late)."""
        bs, fs = self.block_size, self.sample_rate_hz
        src, out = self._source, self._out
        if not self.paced:
            self._fill(src, out)
            with self._lock:
                self._store(out)
            return 0.0
        with self._lock:
            if self._t0 is not None:
                due = self._s0 + (now - self._t0) * fs
                if due > self._written:  # the DAC ran out of samples: it played silence
                    self.underruns += 1
                    self.underrun_s += (due - self._written) / fs
                    self.underruns_audible += self._last_block_sounded
                    self._t0, self._s0 = None, self._written  # re-prime, then restart
            played = self._played(now)
            room = (played // bs) * bs + self.buffer_periods * bs - self._written
        if room >= bs:
            self._fill(src, out)
            with self._lock:
                self._store(out)
                if self._t0 is None and self._written - self._s0 >= self.buffer_periods * bs:
                    self._t0 = now  # primed: the DAC starts
            return 0.0
        # full: until the DAC finishes the block it is playing
        return max(1e-6, self._t0 + ((played // bs + 1) * bs - self._s0) / fs - now)

    # twin extras
    def recording_card(self) -> np.ndarray:
        """Everything played (the last ``record_s``), (n, channels) in sound-card units
        (a column per ``[audio] channels`` name); row k is
        clock ``k`` unless the ring wrapped (then the oldest kept sample comes first)."""
        with self._lock:
            a, b = self._kept_from, self._written
            if b <= a:
                return np.zeros((0, len(self.channels)), np.float32)
            i, j = a % self._cap, b % self._cap
            if i < j:
                return self._rec[i:j].copy()
            return np.concatenate([self._rec[i:], self._rec[:j]])

    def recording_v(self) -> np.ndarray:
        """Everything played, (n, channels) in volts at the piezo patches / screen."""
        return self.recording_card().astype(np.float64) * self._to_v


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
