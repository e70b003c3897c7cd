"""Twin audio output: the table's sound card and amplifiers simulated and recorded.

The audio output pulls blocks from the safety gate and records what the amplifiers got.
Paced (real time), it behaves like a sound card with a device buffer of
``[twin_audio] buffer_periods`` blocks: its thread fills the buffer ahead while the
simulated DAC plays it at the sample rate. The buffer adds ``buffer_periods`` blocks of
output latency, reported in ``status()["latency_s"]`` (the safety gate adds it to its guard
and settle gaps). Fast-forward (not paced) it has no buffer: a block counts as played when
handed over, and it never underruns.

No step beyond the slew limit ever reaches the twin amplifiers, whatever the driver meets:

- An operator's e-stop (a gate event with ``cut``) ramps at the driver: the queued samples
  from the one playing at the event's time are rewritten as a ramp from that sample's
  level to 0 V at the slew step the event gives (``GateEvent.ramp_step_v``, else the
  source's ``ramp_steps_v()``, else the profile's slowest slew limit: every patch
  connected), then zeros. The gate's own ramp down, which starts from the level it last
  handed (a block or more after the sample playing), is dropped (the ramp goes on in its
  place) until the gate hands a block that ends in silence.
- A late block (an underrun: the DAC found the buffer empty, the thread more than
  ``buffer_periods - 1`` blocks late) never steps: the DAC holds the last sample for
  ``UNDERRUN_HOLD_BLOCKS`` block (a late block of up to a period is bridged flat: no
  ramp down and back up for a short hiccup), then ramps from it to 0 at the slew step,
  and when blocks come back (after re-priming the buffer) slew-follows the gate's stream,
  ``y[k] = y[k-1] + clip(x[k] - y[k-1], -s, s)``, until it has caught up.

The recording stays indexed by the gate's clock (row k = clock k, what relay-log clocks
index), holding what was played: the ramps, and the samples after a resume the follower
changed. The gaps themselves are in ``underrun_log`` (clock, length, level, whether it
ramped, cause); ``dac_output_v()`` is the recording with them inserted: what the amplifiers
got in real time. Underruns are counted per cause: ``late_wakeup`` (the driver thread came
back late though its fill was quick) and ``slow_fill`` (the gate's fill itself took longer
than the buffer's slack), and by where the late thread's time went
(``console.core.stall_witness``: the host, the scheduler, its own work, the process).

The relay board it drives the level of is in ``plugins.twin.relays``.
"""

from __future__ import annotations

import math
import sys
import threading
import time
from collections import deque
from collections.abc import Callable
from dataclasses import dataclass
from typing import Any

import numpy as np

from console.plugin_api import (
    ORIGINS,
    PATCHES,
    BlockSource,
    ChannelLayout,
    Limits,
    StallWitness,
    device_buffer_periods,
    realtime_priority,
    summarize_s,
)
from plugins.twin.inputs import TwinInputs
from plugins.twin.relays import bus_for

#: Fast-forward twin: how often an idle driver asks the gate for work: every
#: ``FAST_POLL_S`` right after work (for ``FAST_BUSY_S``: a plan's next step), every
#: ``FAST_IDLE_S`` until ``FAST_QUIET_S`` of idle, then every ``FAST_QUIET_POLL_S`` (an idle
#: table waits for its next request: polling at 5 kHz cost it 15 % of a core, at 500 Hz 5 %)
FAST_POLL_S, FAST_BUSY_S, FAST_IDLE_S = 0.0002, 0.05, 0.002
FAST_QUIET_S, FAST_QUIET_POLL_S = 1.0, 0.01

#: Device buffer of the paced twin, in blocks (a real card's driver fills 2-4 periods ahead).
DEFAULT_BUFFER_PERIODS = 3
#: Seconds of audio the twin keeps for ``recording_v`` (a bounded ring).
DEFAULT_RECORD_S = 120.0
#: An underrun holds the last sample this many blocks before ramping it to 0 V.
UNDERRUN_HOLD_BLOCKS = 1
#: Without the profile's slew limits: a ramp step of this fraction of each channel's full
#: scale per sample (100 samples from full scale to 0 V, well under any slew limit).
FALLBACK_STEP_FRACTION = 0.01
#: Underrun causes counted in ``status()["underruns_by_cause"]``.
UNDERRUN_CAUSES = ("late_wakeup", "slow_fill")


def _key(profile, dotted: str, default):
    try:
        v = profile.get(dotted)
    except Exception:  # a bare profile stub without the section
        v = None
    return default if v is None else v


def _fast_poll_s(idle_s: float) -> float:
    """How long a fast-forward driver idle for ``idle_s`` waits before asking again."""
    if idle_s < FAST_BUSY_S:
        return FAST_POLL_S
    return FAST_IDLE_S if idle_s < FAST_QUIET_S else FAST_QUIET_POLL_S


@dataclass(frozen=True)
class Underrun:
    """One underrun of the paced twin's DAC, as it played it."""

    clock: int  # the gap fell before this sample of the recording
    samples: int  # its length at the DAC
    level_v: tuple[float, ...]  # the sample held (the last played before it), volts
    step_v: tuple[float, ...]  # the ramp's step per sample after the hold, volts
    ramped: bool  # longer than the hold, with signal held: ramped toward 0 V
    cause: str  # one of ``UNDERRUN_CAUSES``
    audible: bool  # it cut into sound (the block before it was not silent)
    origin: str = "unknown"  # where the time went: one of ``stall_witness.ORIGINS``


@dataclass
class _Gap:
    """An underrun under way (card units)."""

    clock: int
    t_out_s: float  # when the DAC played the last queued sample
    level: np.ndarray
    step: np.ndarray
    cause: str
    audible: bool
    origin: str = "unknown"


def _slew_follow(x: np.ndarray, y0: np.ndarray, step: np.ndarray) -> tuple[np.ndarray, bool]:
    """``x`` (n, channels) slew-limited from the level ``y0`` at ``step`` per sample:
    ``y[k] = y[k-1] + clip(x[k] - y[k-1], -step, step)``, then ``x`` itself from the first
    sample where every channel has caught up. Returns ``(y, caught_up)``."""
    y = np.array(x, dtype=np.float32, copy=True)
    prev = np.asarray(y0, dtype=np.float64)
    for k in range(y.shape[0]):
        target = y[k].astype(np.float64)
        d = target - prev
        near = np.abs(d) <= step
        if near.all():
            return y, True  # caught up: the rest is x
        y[k] = np.where(near, target, prev + np.sign(d) * step)
        prev = y[k].astype(np.float64)
    return y, False


def _gap_values(level: np.ndarray, step: np.ndarray, counts: np.ndarray, hold: int) -> np.ndarray:
    """What a gap plays after ``counts`` samples of it, (len(counts), channels): ``level``
    held ``hold`` samples, then ramped to 0 at ``step`` per sample."""
    d = np.maximum(np.asarray(counts, dtype=np.float64) - hold, 0.0)[:, None]
    return np.sign(level)[None, :] * np.maximum(np.abs(level)[None, :] - step[None, :] * d, 0.0)


def _slowest_steps_v(profile, n_ch: int, to_v: np.ndarray) -> np.ndarray:
    """The conservative ramp step (volts per sample, per channel) when neither the e-stop
    event nor the source gives one: the profile's slowest slew limit (every patch
    connected), else ``FALLBACK_STEP_FRACTION`` of full scale."""
    try:
        steps = np.asarray(Limits.from_profile(profile).column_steps_v(frozenset(PATCHES)))
        if steps.shape == (n_ch,) and np.all(np.isfinite(steps)) and np.all(steps > 0):
            return steps.astype(np.float64)
    except Exception:  # a bare profile stub without the limits
        pass
    return to_v.astype(np.float64) * FALLBACK_STEP_FRACTION


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
            own = _key(profile, "twin_audio.buffer_periods", DEFAULT_BUFFER_PERIODS)
            buffer_periods = device_buffer_periods(profile, own)  # [audio] buffer_ms wins
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
        # the ring, indexed by clock; paced, its pages are touched at start (``start``)
        self._rec = np.zeros((self._cap, n_ch), dtype=np.float32)
        self._touched = False
        self._lock = threading.Lock()
        self._written = 0  # samples handed over by the gate (= the recording's clock)
        self._kept_from = 0  # oldest clock still in the ring
        self._t0: float | None = None  # DAC clock: sample _s0 played at _t0 (None: priming)
        self._s0 = 0
        #: the ramp step when neither an e-stop event nor the source gives one (card units)
        self._default_step = _slowest_steps_v(profile, n_ch, self._to_v) / self._to_v
        self._step = self._default_step.copy()  # the slew follower's step (card units)
        # the slew follower is on: blocks stored are slew-limited from the last sample
        # (after an e-stop's ramp or an underrun, until it has caught up with the gate)
        self._follow = False
        # an operator's e-stop cut the output: the gate's blocks are replaced by silence
        # (the follower ramps to it) until its ramp down is over (a block ending in silence)
        self._cutting = False
        self._filling = False  # the driver is inside the gate's fill (a block under way)
        self._handed_silent = True  # the last block the gate handed ended at 0 V everywhere
        self._gap: _Gap | None = None  # an underrun under way (the DAC re-primes)
        self.hold_samples = UNDERRUN_HOLD_BLOCKS * bs
        self._thread: threading.Thread | None = None
        self._stop = threading.Event()
        self.realtime_priority = False
        self.underruns = 0
        self.underrun_s = 0.0  # gap the DAC played while the buffer was empty
        self.underruns_audible = 0  # ... of them, cutting into output (the last block not silent)
        self.underruns_by_cause: dict[str, int] = dict.fromkeys(UNDERRUN_CAUSES, 0)
        #: ... and by where the late thread's time went (``console.core.stall_witness``)
        self.underruns_by_origin: dict[str, int] = dict.fromkeys(ORIGINS, 0)
        self._witness: StallWitness | None = None  # the paced driver thread's own
        self.underrun_log: deque[Underrun] = deque(maxlen=10_000)
        self._last_block_sounded = False
        self.blocks = 0
        self.callback_s: deque[float] = deque(maxlen=4096)
        #: the clock the gate's fill is timed with (a test may drive it)
        self.fill_clock: Callable[[], float] = time.perf_counter
        self._last_fill_s = 0.0
        self._source: BlockSource | None = None
        self._out = np.zeros((self.block_size, n_ch), dtype=np.float32)
        self._zeros = np.zeros_like(self._out)
        self.inputs = TwinInputs(profile, self)  # duplex: computed when read, never here

    # AudioOutput protocol
    def start(self, source: BlockSource) -> None:
        if self._thread is not None:
            return
        self._source = source
        if self.paced and not self._touched:
            # here, not first in the audio thread: touching fresh pages there (each new
            # 2 MB huge page zeroed on demand) stalled it 5-7 ms every ~5 s: underruns.
            # Fast-forward has no deadline: its pages come as they are used.
            self._rec.fill(0.0)
            self._touched = True
        with self._lock:
            self._t0, self._s0 = None, self._written
        self._bus.level_v = (0.0,) * len(self.channels)
        self._bus.drive(self._probe)  # this output drives the wire from now on
        self._listen(source, True)
        self._stop.clear()
        self._thread = threading.Thread(target=self._run, name="haptable-twin-audio", daemon=True)
        self._thread.start()

    def stop(self) -> None:
        self._stop.set()
        if self._thread is not None and self._thread is not threading.current_thread():
            self._thread.join(timeout=2.0)
        self._thread = None
        with self._lock:  # the DAC plays out what was queued
            if self._gap is not None:
                self._end_gap(time.monotonic())
            self._t0 = None
            self._s0 = self._written
        self._listen(self._source, False)
        self._bus.release(self._probe)

    def _listen(self, source: Any, on: bool) -> None:
        """Hear the gate's events (``add_listener`` / ``remove_listener``, or a plain
        ``listeners`` list on a stand-in) from ``start`` until ``stop``."""
        fn = self._on_gate_event
        method = getattr(source, "add_listener" if on else "remove_listener", None)
        if callable(method):
            method(fn)
            return
        listeners = getattr(source, "listeners", None)
        if isinstance(listeners, list):
            if on and fn not in listeners:
                listeners.append(fn)
            elif not on and fn in listeners:
                listeners.remove(fn)

    @property
    def latency_s(self) -> float:
        """Handing a sample over -> it has been played (at most): the device buffer."""
        periods = self.buffer_periods if self.paced else 1
        return periods * self.block_size / self.sample_rate_hz

    @property
    def slack_s(self) -> float:
        """How late the driver thread may be before the DAC starves: the buffer less the
        block it plays."""
        return (self.buffer_periods - 1) * self.block_size / self.sample_rate_hz

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
            "underruns_by_cause": dict(self.underruns_by_cause),
            "underruns_by_origin": dict(self.underruns_by_origin),
            "underrun_hold_s": self.hold_samples / self.sample_rate_hz,
            # the last few gaps: when (the gate's clock), how long, why, heard or not
            "underrun_last": [
                [g.clock, g.samples, g.cause, g.audible, g.origin]
                for g in list(self.underrun_log)[-8:]
            ],
            "blocks": self.blocks,
            # the gate's fill per block, as this driver timed it (the last 4096 blocks)
            "fill_ms": summarize_s(list(self.callback_s)),
        }

    # the simulated DAC ---------------------------------------------------------------
    def _played(self, now: float) -> int:
        """Clock of the sample the DAC plays at ``now`` (caller holds the lock)."""
        if not self.paced:
            return self._written
        if self._t0 is None:
            return self._s0
        return min(self._written, self._s0 + int((now - self._t0) * self.sample_rate_hz + 1e-6))

    def _last(self) -> np.ndarray:
        """The last sample stored, card units (caller holds the lock)."""
        if self._written == 0 or self._written <= self._kept_from:
            return np.zeros(len(self.channels))
        return self._rec[(self._written - 1) % self._cap].astype(np.float64)

    def _gap_now(self, now: float) -> np.ndarray | None:
        """The level the DAC puts out at ``now`` in a gap (card units), or ``None`` when it
        is playing queued samples (caller holds the lock)."""
        fs = self.sample_rate_hz
        g = self._gap
        if g is not None:
            t_out, level, step = g.t_out_s, g.level, g.step
        elif (
            self.paced
            and self._t0 is not None
            and (self._s0 + (now - self._t0) * fs > self._written)
        ):  # ran out, not noticed by the driver thread yet
            t_out = self._t0 + (self._written - self._s0) / fs
            level, step = self._last(), self._step
        else:
            return None
        n = max(0, int((now - t_out) * fs))
        return _gap_values(level, step, np.array([n]), self.hold_samples)[0]

    def _probe(self, now: float | None = None) -> tuple[int, tuple[float, ...]]:
        """The clock of the sample at the amplifiers at ``now`` (default: now) and the
        level they put out then (a gap's hold or ramp included), volts."""
        with self._lock:
            now = time.monotonic() if now is None else now
            p = self._played(now)
            gap = self._gap_now(now)
            if gap is not None:
                lvl = tuple(float(v) for v in gap * self._to_v)
            elif p <= self._kept_from or p == 0:
                lvl = (0.0,) * len(self.channels)
            else:
                x = self._rec[(p - 1) % self._cap] * self._to_v
                lvl = tuple(float(v) for v in x)
        return p, lvl

    def _steps(self, steps_v: Any) -> np.ndarray | None:
        """A slew step per channel in volts as card units, or ``None`` if it is none."""
        try:
            s = np.asarray(steps_v, dtype=np.float64)
        except (TypeError, ValueError):
            return None
        if s.shape != (len(self.channels),) or not np.all(np.isfinite(s)) or np.any(s <= 0):
            return None
        return s / self._to_v

    def _source_steps(self) -> np.ndarray | None:
        """The source's slew steps for its relays now (``ramp_steps_v()``), card units."""
        fn = getattr(self._source, "ramp_steps_v", None)
        if not callable(fn):
            return None
        try:
            return self._steps(fn())
        except Exception:  # a source that cannot say: the default
            return None

    def _on_gate_event(self, ev: Any) -> None:
        """E-stop: ramp to 0 V from the sample playing now, at the event's slew step."""
        if getattr(ev, "kind", "") not in ("estop", "shutdown") or not getattr(ev, "cut", True):
            return  # a fault's e-stop: the gate's ramp to zero plays out
        t = getattr(ev, "t_s", None) or time.monotonic()  # the moment of the e-stop
        step = self._steps(getattr(ev, "ramp_step_v", ()))
        if step is None:  # outside the lock: the source may take its own
            step = self._source_steps()
        if step is None:
            step = self._default_step
        with self._lock:
            self._step = step  # (a gap under way keeps its own: its ramp never jumps)
            p = max(self._played(t), self._kept_from, self._written - self._cap)
            if self._gap_now(t) is not None:
                # the DAC is in a gap (it holds, then ramps): what is queued is not playing
                # yet; silence as the follower's target, it ramps there when blocks resume
                self._ring_write(p, np.zeros((self._written - p, len(self.channels))))
            elif p < self._written:
                n_ch = len(self.channels)
                level = self._rec[(p - 1) % self._cap].astype(np.float64) if p else np.zeros(n_ch)
                ramp, _ = _slew_follow(np.zeros((self._written - p, n_ch)), level, step)
                self._ring_write(p, ramp)
            self._follow = self._follow or bool(np.any(self._last() != 0))
            # a block under way now may have been filled before the gate saw its e-stop
            # (signal), and every later one is the gate's ramp from the level it last
            # handed: replaced by silence (which the follower ramps to), unless the gate was
            # silent and nothing is under way. (A fill that starts after this reads the
            # e-stop: it ramps from that level.)
            self._cutting = self._cutting or self._filling or not self._handed_silent

    def _ring_read(self, a: int, b: int) -> np.ndarray:
        """Clocks ``a..b`` of the ring, a copy (caller holds the lock)."""
        i, j = a % self._cap, b % self._cap
        if b - a <= 0:
            return self._rec[:0].copy()
        if i < j:
            return self._rec[i:j].copy()
        return np.concatenate([self._rec[i:], self._rec[:j]])

    def _ring_write(self, a: int, x: np.ndarray) -> None:
        """Store ``x`` at clocks ``a..a+len(x)`` of the ring (caller holds the lock)."""
        n = x.shape[0]
        if n <= 0:
            return
        i = a % self._cap
        first = min(n, self._cap - i)
        self._rec[i : i + first] = x[:first]
        self._rec[: n - first] = x[first:]

    def _store(self, out: np.ndarray) -> None:
        """Queue a filled block (caller holds the lock)."""
        n = out.shape[0]
        x = self._zeros[:n] if self._cutting else out
        if self._follow and self._gap is None:  # (in a gap: at the restart, from its end)
            x, caught = _slew_follow(x, self._last(), self._step)
            self._follow = not caught
        self._ring_write(self._written, x)
        self._last_block_sounded = bool(x.any())
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
        clock = self.fill_clock
        t0 = clock()
        src.fill(out)
        self._last_fill_s = clock() - t0
        self.callback_s.append(self._last_fill_s)

    def _begin_gap(self, t_out: float, origin: str = "unknown") -> _Gap:
        """The DAC ran out at ``t_out``: it holds the last sample (caller holds the lock)."""
        cause = "slow_fill" if self._last_fill_s > self.slack_s else "late_wakeup"
        g = _Gap(
            self._written, t_out, self._last(), self._step, cause, self._last_block_sounded, origin
        )
        self._gap = g
        self.underruns += 1
        self.underruns_by_cause[cause] = self.underruns_by_cause.get(cause, 0) + 1
        self.underruns_by_origin[origin] = self.underruns_by_origin.get(origin, 0) + 1
        self.underruns_audible += g.audible
        self._t0, self._s0 = None, self._written  # re-prime, then restart
        return g

    def _end_gap(self, now: float) -> None:
        """The DAC restarts at ``now``: log the gap and slew-follow the queued samples from
        the level it ended at (caller holds the lock)."""
        g, self._gap = self._gap, None
        if g is None:
            return
        n = max(0, int(round((now - g.t_out_s) * self.sample_rate_hz)))
        end = _gap_values(g.level, g.step, np.array([n]), self.hold_samples)[0]
        a = max(g.clock, self._kept_from)
        y, caught = _slew_follow(self._ring_read(a, self._written), end, g.step)
        self._ring_write(a, y)
        self._follow = not caught
        self.underrun_s += n / self.sample_rate_hz
        to_v = self._to_v.astype(np.float64)
        self.underrun_log.append(
            Underrun(
                clock=g.clock,
                samples=n,
                level_v=tuple(float(v) for v in g.level * to_v),
                step_v=tuple(float(v) for v in g.step * to_v),
                ramped=n > self.hold_samples and bool(np.any(g.level != 0)),
                cause=g.cause,
                audible=g.audible,
                origin=g.origin,
            )
        )

    def _run(self) -> None:
        src = self._source
        if self.paced:
            self.realtime_priority = realtime_priority()
            # the driver thread needs the GIL within its slack ((buffer_periods - 1) blocks):
            # Python hands it over only every switch interval (5 ms by default)
            if sys.getswitchinterval() > self.slack_s / 2:
                sys.setswitchinterval(self.slack_s / 2)
            self._witness = StallWitness()
        try:
            self._loop(src)
        finally:
            if self._witness is not None:
                self._witness.close()
                self._witness = None

    def _loop(self, src: BlockSource) -> None:
        idle_since: float | None = None
        while not self._stop.is_set():
            if not self.paced:
                if src.idle:  # fast-forward: the clock only runs while there is work
                    now = time.monotonic()
                    if idle_since is None:
                        idle_since = now
                    self._stop.wait(_fast_poll_s(now - idle_since))
                    continue
                idle_since = None
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
        gap = None
        witness = self._witness
        if witness is not None and threading.current_thread() is not self._thread:
            witness = None  # (a test stepping the driver: the witness is the thread's)

        def origin() -> str:
            return witness.why(self.slack_s) if witness is not None else "unknown"

        with self._lock:
            if self._t0 is not None:
                due = self._s0 + (now - self._t0) * fs
                if due > self._written:  # the DAC ran out: it holds, then ramps to 0 V
                    gap = self._begin_gap(self._t0 + (self._written - self._s0) / fs, origin())
            played = self._played(now)
            room = (played // bs) * bs + self.buffer_periods * bs - self._written
        if witness is not None:  # the next cycle's lateness is judged from here
            witness.note()
        if gap is not None:  # the slew step for the relays now (outside the lock)
            step = self._source_steps()
            with self._lock:
                if step is not None:
                    gap.step = self._step = step
        if room >= bs:
            self._fill(src, out)
            with self._lock:
                self._store(out)
                if self._t0 is None and self._written - self._s0 >= self.buffer_periods * bs:
                    self._end_gap(now)
                    self._t0 = now  # primed: the DAC starts
            return 0.0
        # full: until the DAC finishes the block it is playing
        return max(1e-6, self._t0 + ((played // bs + 1) * bs - self._s0) / fs - now)

    # duplex inputs (``console.core.contracts.RecordsInputs``; ``plugins.twin.inputs``)
    @property
    def input_specs(self) -> tuple:
        return self.inputs.specs

    def input_clock(self) -> int:
        """Inputs are ready for the clocks before this one (the DAC has played them)."""
        with self._lock:
            return self._played(time.monotonic())

    def read_inputs(self, a: int, b: int) -> np.ndarray:
        """The inputs over clocks ``a..b``, (b - a, inputs) float32 card units."""
        return self.inputs.read(a, b)

    @property
    def to_v(self) -> np.ndarray:
        """Volts at the actuator per card unit, per output channel."""
        return self._to_v

    @property
    def board(self) -> Any:
        """The twin relay board on this output's wire (None: none yet)."""
        return self._bus.board

    def played_card(self, a: int, b: int) -> np.ndarray:
        """Clocks ``a..b`` of the recording, card units (zeros outside what is kept)."""
        out = np.zeros((max(0, b - a), len(self.channels)), np.float32)
        with self._lock:
            lo, hi = max(a, self._kept_from), min(b, self._written)
        if hi <= lo:
            return out
        # the bulk copied outside the lock (as ``_snapshot``: a long record copied under
        # it would keep the DAC thread waiting), the last blocks under it
        mid = max(lo, hi - (self.buffer_periods + 1) * self.block_size)
        chunk = self.sample_rate_hz // 4
        for c in range(lo, mid, chunk):
            e = min(mid, c + chunk)
            out[c - a : e - a] = self._ring_view(c, e)
        with self._lock:
            out[mid - a : hi - a] = self._ring_read(mid, hi)
            lost = self._kept_from - lo  # the ring wrapped over them during the copy
        if lost > 0:
            out[lo - a : lo - a + lost] = 0.0
        return out

    # twin extras
    def recording_card(self, since: int = 0) -> np.ndarray:
        """Everything played (the last ``record_s``), (n, channels) in sound-card units
        (a column per ``[audio] channels`` name); row k is
        clock ``k`` unless the ring wrapped (then the oldest kept sample comes first).
        ``since``: only the rows from that one on (what a reader polling for new samples
        has not seen yet)."""
        return self._snapshot(since)[1]

    def _snapshot(self, since: int = 0) -> tuple[int, np.ndarray]:
        """(clock of the first row, rows ``since`` on) of the ring, copied without holding
        the driver thread: the bulk in chunks outside the lock (a 120 s recording is
        ~100 MB: copied under the lock, or in one call that keeps the interpreter, it
        would starve the DAC), then under the lock the last blocks, which an e-stop or an
        underrun may still rewrite, and the check that the ring did not overwrite the
        oldest rows meanwhile (those are dropped)."""
        with self._lock:
            a, b = self._kept_from + max(0, since), self._written
        if b <= a:
            return a, np.zeros((0, len(self.channels)), np.float32)
        tail = (self.buffer_periods + 1) * self.block_size
        mid = max(a, b - tail)
        out = np.empty((b - a, len(self.channels)), np.float32)
        chunk = self.sample_rate_hz // 4  # a quarter second: ~100 us to copy
        for c in range(a, mid, chunk):
            e = min(mid, c + chunk)
            out[c - a : e - a] = self._ring_view(c, e)
        with self._lock:
            out[mid - a :] = self._ring_read(mid, b)
            lost = self._kept_from - a  # the ring wrapped over them during the copy
        return (a, out) if lost <= 0 else (a + lost, out[lost:])

    def _ring_view(self, a: int, b: int) -> np.ndarray:
        """Clocks ``a..b`` of the ring as stored (no lock; the two pieces when it wraps)."""
        i, j = a % self._cap, b % self._cap
        return self._rec[i:j] if i < j else np.concatenate([self._rec[i:], self._rec[:j]])

    def recording_v(self) -> np.ndarray:
        """Everything played, (n, channels) in volts at the piezo patches / screen."""
        return self.recording_card().astype(np.float64) * self._to_v

    def dac_output_v(self) -> np.ndarray:
        """What the amplifiers got in real time, (n, channels) volts: the recording with
        every logged underrun's gap (the held sample, then the ramp to 0 V) inserted where
        it fell. Not indexed by the gate's clock (use ``recording_v`` for that)."""
        a, card = self._snapshot()
        with self._lock:
            gaps = [g for g in self.underrun_log if g.clock >= a]
        rec = card.astype(np.float64) * self._to_v
        parts, i = [], 0
        for g in gaps:
            j = g.clock - a
            parts += [rec[i:j], self._gap_v(g)]
            i = j
        parts.append(rec[i:])
        return np.concatenate(parts)

    def dac_output_card(self) -> np.ndarray:
        """``dac_output_v`` in sound-card units, float32 (what the kernel sends a client)."""
        return (self.dac_output_v() / self._to_v).astype(np.float32)

    def _gap_v(self, g: Underrun) -> np.ndarray:
        level, step = np.array(g.level_v), np.array(g.step_v)
        return _gap_values(level, step, np.arange(1, g.samples + 1), self.hold_samples)
