"""The safety gate: the only path from effects to the amplifiers and relays.

- Plans are checked before they play: over a limit, NaN/inf, a step faster than the slew
  limit anywhere, or not starting and ending at zero through a ramp -> refused with a
  message, never clipped. What plays is the private read-only copy that was checked.
- Every audio block, whatever produced it (a plan, a stream, an attached source), is
  checked again on its way to the driver: finite numbers, limits, the slew limit against
  the last sample handed out, screen signal only with the screen relay closed. A bad
  block trips the e-stop and the driver gets a ramp to zero at the slew limit.
- The slew limit comes from the physics: the amplifier's peak current and the relay's
  current rating into the capacitance of the loads the relays connect (dV/dt = I / C).
- Plugin code never runs on the audio thread unguarded: an attached source is called on a
  thread of its own and the driver never waits for it longer than ``[limits]
  source_stall_ms`` (an e-stop ends the wait at once).
- Relays switch only while the samples handed to the driver have been zero for the guard
  gap (plus the device latency), at most once per ``[relays] min_switch_interval_ms`` per
  channel; the gate holds the outputs silent while a switch is under way and for the
  settle time after it, whatever a plugin asks.
- E-stop ramps the outputs to zero from the next audio block, then opens every relay once
  that silence has been handed to the driver. It is idempotent, and also runs on an
  unhandled exception, on SIGINT/SIGTERM and at exit.
"""

from __future__ import annotations

import atexit
import logging
import math
import queue
import signal
import sys
import threading
import time
import weakref
from collections import deque
from collections.abc import Callable
from dataclasses import dataclass, field
from typing import TYPE_CHECKING, Any

import numpy as np

from console.contracts import RelayBoard
from console.errors import SafetyRefusal
from console.types import PATCHES, OutputPlan

if TYPE_CHECKING:
    from console.profile import Profile

log = logging.getLogger("haptable.safety")
RAMP_TOLERANCE = 1.02  # a sine under a linear envelope may touch the envelope


@dataclass(frozen=True)
class Limits:
    """Per-channel limits in volts at the actuator, and the timing rules."""

    sample_rate_hz: int
    piezo_min_v: float
    piezo_max_v: float
    screen_max_v: float  # peak, = screen_max_vpp / 2
    piezo_card_v: float  # the largest |volts| the sound card + amplifier can produce
    screen_card_v: float
    rating_vpp: float
    ramp_samples: int
    max_plan_samples: int
    guard_samples: int
    settle_samples: int  # switch time + guard after a switch
    estop_timeout_s: float
    # slew: dV/dt = I / C, per amplifier and per relay channel
    piezo_current_a: float = 0.2
    screen_current_a: float = 0.2
    relay_current_a: float = 0.1
    patch_capacitance_f: dict[str, float] = field(default_factory=dict)
    patch_relay: dict[str, int] = field(default_factory=dict)
    screen_capacitance_f: float = 200e-9
    min_switch_interval_samples: int = 0
    source_stall_s: float = 0.1

    @classmethod
    def from_profile(cls, profile: Profile) -> Limits:
        fs = int(profile.get("audio.sample_rate_hz"))
        full = float(profile.get("audio.full_scale_v"))
        guard = profile.get("relays.guard_ms") * 1e-3
        switch = profile.get("relays.switch_time_ms") * 1e-3
        patches = profile.items("patches")
        return cls(
            sample_rate_hz=fs,
            piezo_min_v=float(profile.get("limits.piezo_min_v")),
            piezo_max_v=float(profile.get("limits.piezo_max_v")),
            screen_max_v=float(profile.get("limits.screen_max_vpp")) / 2,
            piezo_card_v=full * float(profile.get("amplifiers.piezo_gain")),
            screen_card_v=full * float(profile.get("amplifiers.screen_gain")),
            rating_vpp=float(profile.get("relays.rating_vpp")),
            ramp_samples=max(1, round(profile.get("limits.ramp_min_ms") * 1e-3 * fs)),
            max_plan_samples=round(profile.get("limits.max_plan_s") * fs),
            guard_samples=round(guard * fs),
            settle_samples=round((guard + switch) * fs),
            estop_timeout_s=profile.get("limits.estop_timeout_ms") * 1e-3,
            piezo_current_a=float(profile.get("amplifiers.piezo_peak_current_ma")) * 1e-3,
            screen_current_a=float(profile.get("amplifiers.screen_peak_current_ma")) * 1e-3,
            relay_current_a=float(profile.get("relays.current_rating_ma")) * 1e-3,
            patch_capacitance_f={n: float(p["capacitance_nf"]) * 1e-9 for n, p in patches.items()},
            patch_relay={n: int(p["relay_channel"]) for n, p in patches.items()},
            screen_capacitance_f=float(profile.get("screen.capacitance_nf")) * 1e-9,
            min_switch_interval_samples=round(
                profile.get("relays.min_switch_interval_ms") * 1e-3 * fs
            ),
            source_stall_s=float(profile.get("limits.source_stall_ms")) * 1e-3,
        )

    def slew_v_per_s(self, channel: str, patches: frozenset[str] = frozenset()) -> float:
        """Fastest change the channel may make: the amplifier's peak current into every
        load it drives, and each relay channel's current rating into the loads behind it."""
        if channel == "screen":
            c = self.screen_capacitance_f
            return min(self.screen_current_a, self.relay_current_a) / c
        caps = self.patch_capacitance_f or {p: 90e-9 for p in PATCHES}
        chosen = [p for p in patches if p in caps] or [max(caps, key=caps.__getitem__)]
        per_relay: dict[int | str, float] = {}
        for p in chosen:
            ch = self.patch_relay.get(p, p)
            per_relay[ch] = per_relay.get(ch, 0.0) + caps[p]
        total = sum(caps[p] for p in chosen)
        return min(self.piezo_current_a / total, self.relay_current_a / max(per_relay.values()))

    def max_step_v(self, channel: str, patches: frozenset[str] = frozenset()) -> float:
        """The slew limit as the largest change from one sample to the next, in volts."""
        return self.slew_v_per_s(channel, patches) / self.sample_rate_hz

    def piezo_range(self) -> tuple[float, float]:
        return max(self.piezo_min_v, -self.piezo_card_v), min(self.piezo_max_v, self.piezo_card_v)

    def screen_range(self) -> tuple[float, float]:
        peak = min(self.screen_max_v, self.screen_card_v)
        return -peak, peak


def _range_problem(x: np.ndarray, lo: float, hi: float, rating_vpp: float) -> str | None:
    bad = np.flatnonzero(~np.isfinite(x))
    if bad.size:
        return f"NaN/inf at sample {int(bad[0])}"
    if x.size == 0:
        return None
    mn, mx = float(x.min()), float(x.max())
    if mn < lo - 1e-9 or mx > hi + 1e-9:
        k = int(np.argmax((x < lo - 1e-9) | (x > hi + 1e-9)))
        return f"{x[k]:.1f} V at sample {k} is outside {lo:g}..{hi:g} V"
    if mx - mn > rating_vpp + 1e-9:
        return f"{mx - mn:.1f} Vpp exceeds the relay rating {rating_vpp:g} Vpp"
    return None


def _slew_problem(x: np.ndarray, prev: float, max_step: float, *, end: bool) -> str | None:
    """A change from one sample to the next (from ``prev``; to 0 after the end when
    ``end``) larger than ``max_step`` volts."""
    if x.size == 0:
        return None
    d = np.abs(np.diff(x, prepend=prev, append=0.0 if end else x[-1]))
    tol = max_step * 1e-9 + 1e-9
    over = np.flatnonzero(d > max_step + tol)
    if not over.size:
        return None
    k = int(over[0])
    return (
        f"steps {float(d[k]):.2f} V in one sample at sample {k}, over its slew limit of "
        f"{max_step:.2f} V per sample (amplifier/relay current into the load capacitance); "
        f"smooth the edge"
    )


def _ramp_problem(x: np.ndarray, ramp: int) -> str | None:
    """Start and end at zero, under a linear envelope ``ramp`` samples long."""
    peak = float(np.max(np.abs(x))) if x.size else 0.0
    if peak == 0.0:
        return None
    tol = 1e-6 * peak + 1e-9
    if abs(x[0]) > tol or abs(x[-1]) > tol:
        which = "start" if abs(x[0]) > tol else "end"
        return f"does not {which} at zero ({x[0] if which == 'start' else x[-1]:.3g} V)"
    n = min(ramp, x.size)
    env = peak * (np.arange(n) / ramp) * RAMP_TOLERANCE + tol
    head, tail = np.abs(x[:n]), np.abs(x[::-1][:n])
    for part, seg in (("start", head), ("end", tail)):
        over = np.flatnonzero(seg > env)
        if over.size:
            return (
                f"rises faster than a {ramp}-sample ramp at its {part} "
                f"(sample {int(over[0])} of the {part}); add a linear ramp"
            )
    return None


def check_plan(plan: OutputPlan, limits: Limits) -> None:
    """Refuse a plan the outputs must not play. Raises ``SafetyRefusal``."""
    name = plan.name or "plan"
    gap_s = plan.gap_s
    if not isinstance(gap_s, (int, float)) or not math.isfinite(gap_s) or gap_s < 0:
        raise SafetyRefusal(f"{name}: gap_s = {gap_s!r}: must be a finite number of seconds >= 0")
    n_total = sum(int(np.size(getattr(seg, "piezo_v", ()))) for seg in plan.segments)
    n_total += round(gap_s * limits.sample_rate_hz) * max(len(plan.segments) - 1, 0)
    if n_total > limits.max_plan_samples:
        raise SafetyRefusal(
            f"{name}: {n_total / limits.sample_rate_hz:.1f} s is longer than [limits] max_plan_s"
        )
    if plan.sample_rate_hz != limits.sample_rate_hz:
        raise SafetyRefusal(
            f"{name}: sample rate {plan.sample_rate_hz} Hz, but the output runs at "
            f"{limits.sample_rate_hz} Hz; render it at [audio] sample_rate_hz"
        )
    if not plan.segments:
        raise SafetyRefusal(f"{name}: no segments to play")
    total = 0
    for i, seg in enumerate(plan.segments, 1):
        label = f"{name}: segment {i}" + (f" ({seg.label})" if seg.label else "")
        unknown = set(seg.patches) - set(PATCHES)
        if unknown:
            raise SafetyRefusal(f"{label}: unknown patches {sorted(unknown)}; use {PATCHES}")
        arrays = {}
        for ch in ("piezo_v", "screen_v"):
            a = np.asarray(getattr(seg, ch))
            if a.ndim != 1 or not np.issubdtype(a.dtype, np.number):
                raise SafetyRefusal(f"{label}: {ch} must be a 1-D array of volts")
            arrays[ch] = a.astype(float, copy=False)
        if arrays["piezo_v"].size != arrays["screen_v"].size:
            raise SafetyRefusal(f"{label}: piezo and screen channels differ in length")
        total += arrays["piezo_v"].size
        patches = frozenset(seg.patches)
        for ch, (lo, hi) in (
            ("piezo_v", limits.piezo_range()),
            ("screen_v", limits.screen_range()),
        ):
            x = arrays[ch]
            chan = ch.split("_")[0]
            if (p := _range_problem(x, lo, hi, limits.rating_vpp)) is not None:
                raise SafetyRefusal(f"{label}: {chan} channel {p}")
            if (p := _ramp_problem(x, limits.ramp_samples)) is not None:
                raise SafetyRefusal(f"{label}: {chan} channel {p}")
            step = limits.max_step_v(chan, patches)
            if (p := _slew_problem(x, 0.0, step, end=True)) is not None:
                raise SafetyRefusal(f"{label}: {chan} channel {p}")
        if np.any(arrays["piezo_v"]) and not seg.patches:
            raise SafetyRefusal(f"{label}: piezo signal with no patch selected")
        if np.any(arrays["screen_v"]) and not seg.screen:
            raise SafetyRefusal(f"{label}: screen signal with the screen relay open")
    if total > limits.max_plan_samples:
        raise SafetyRefusal(
            f"{name}: {total / limits.sample_rate_hz:.1f} s is longer than [limits] max_plan_s"
        )


class Source:
    """What the gate pulls samples from (the output scheduler)."""

    def next_block(self, n: int) -> tuple[np.ndarray, np.ndarray] | None:  # pragma: no cover
        raise NotImplementedError

    @property
    def idle(self) -> bool:  # pragma: no cover
        return True

    def abort(self, reason: str) -> None:  # pragma: no cover
        """Drop everything queued (called by the e-stop)."""


class SourceStalled(Exception):
    """A source did not answer within its time (or is still inside an earlier call)."""


class SourceInterrupted(Exception):
    """An e-stop ended the wait for a source."""


class SourceCaller:
    """Runs plugin code (``fn(n)``) on a thread of its own so that it never holds the audio
    thread: the caller waits at most ``timeout_s``, or until ``interrupt()`` (the e-stop).
    A call that is still running makes every later call fail at once (the source stalled);
    its late result is dropped. The hand-over is two C-level queues (no Python locks)."""

    def __init__(self, name: str) -> None:
        self.name = name
        self._req: queue.SimpleQueue = queue.SimpleQueue()
        self._res: queue.SimpleQueue = queue.SimpleQueue()
        self._busy = False
        self._gen = 0
        self._interrupts = 0
        self._thread: threading.Thread | None = None

    def call(self, fn: Callable[[int], Any], n: int, timeout_s: float) -> Any:
        if self._busy:
            raise SourceStalled(f"{self.name} is still inside an earlier call")
        if self._thread is None:
            self._thread = threading.Thread(target=self._run, name=self.name, daemon=True)
            self._thread.start()
        self._gen += 1
        gen, seen = self._gen, self._interrupts
        self._busy = True
        self._req.put((gen, fn, n))
        deadline = time.monotonic() + timeout_s
        while True:
            left = deadline - time.monotonic()
            if left <= 0:
                raise SourceStalled(
                    f"{self.name} gave no block within {timeout_s * 1e3:.0f} ms "
                    f"([limits] source_stall_ms)"
                )
            try:
                item = self._res.get(timeout=left)
            except queue.Empty:
                continue
            if item[0] == "interrupt":
                if item[1] > seen:
                    raise SourceInterrupted(f"{self.name}: interrupted by the e-stop")
                continue
            if item[0] != gen:
                continue  # the late answer to an abandoned call
            if not item[1]:
                raise item[2]
            return item[2]

    def interrupt(self) -> None:
        self._interrupts += 1
        self._res.put(("interrupt", self._interrupts))

    def _run(self) -> None:
        from console.realtime import AUDIO_PRIORITY, realtime_priority

        realtime_priority(AUDIO_PRIORITY)  # it stands in for the audio thread
        while True:
            gen, fn, n = self._req.get()
            try:
                res: tuple[bool, Any] = (True, fn(n))
            except BaseException as exc:  # handed to the caller, never lost
                res = (False, exc)
            self._busy = False
            self._res.put((gen, *res))


@dataclass(frozen=True)
class GateEvent:
    t_s: float
    clock: int
    kind: str  # "estop", "refused", "switch", "fault", "reset"
    message: str
    #: an e-stop a driver may answer by dropping its queued blocks at once (an operator's);
    #: a fault's e-stop is not cut: the gate's ramp to zero at the slew limit plays out
    cut: bool = True


_LIVE_GATES: weakref.WeakSet[SafetyGate] = weakref.WeakSet()


def _as_volts(x: Any, n: int, name: str) -> tuple[np.ndarray | None, str | None]:
    """A block channel as a float array of ``n`` samples, or why it is not one."""
    try:
        a = np.asarray(x)
    except Exception as exc:
        return None, f"{name} block is not an array ({type(exc).__name__})"
    if a.dtype.kind not in "fiu":
        return None, f"{name} block has dtype {a.dtype}, not numbers"
    if a.shape != (n,):
        return None, f"output block has shape {a.shape} on the {name} channel, expected ({n},)"
    return a.astype(np.float64, copy=False), None


class SafetyGate:
    """Owns the relay board, checks every block, and holds the e-stop.

    ``fill(out)`` is what the audio driver calls. The scheduler attaches itself; any other
    source (``attach(source)``) is called on a guarded thread and checked the same way.
    Only the gate ever calls ``board.set``.
    """

    def __init__(
        self,
        limits: Limits,
        board: RelayBoard | None,
        *,
        relay_channels: dict[str, int] | None = None,
        screen_channel: int | None = None,
        latency_samples: int = 0,
    ) -> None:
        self.limits = limits
        self._board = board
        self.relay_channels = dict(relay_channels or {})
        self.screen_channel = screen_channel
        self.latency_samples = latency_samples
        self._lock = threading.RLock()
        # held across a relay switch: an e-stop opening the relays waits for a switch in
        # flight to finish, so a late command can never close a relay after the e-stop
        self._switch_lock = threading.RLock()
        self._source: Source | None = None
        self._caller: SourceCaller | None = None  # set for sources other than the scheduler
        self._estopped = False
        self.estop_reason = ""
        self._switching = False
        self.clock = 0  # samples handed to the driver
        self._last_nonzero = -(10**12)
        self._quiet_until = 0  # no signal before this clock (post-switch settle)
        self._last_switch: dict[int, int] = {}  # channel -> clock of its last switch
        self._steps_for: tuple | None = None  # _max_steps() for one relay state
        self.level_v = (0.0, 0.0)  # last sample handed out, volts at the actuators
        self.relays: tuple[bool, ...] = tuple(board.states()) if board else ()
        self.events: deque[GateEvent] = deque(maxlen=1000)
        self._safe = threading.Event()
        self._safe.set()
        self._audio_thread: threading.Thread | None = None
        self.listeners: list[Callable[[GateEvent], None]] = []
        self._piezo_scale = 1.0 / limits.piezo_card_v
        self._screen_scale = 1.0 / limits.screen_card_v
        _LIVE_GATES.add(self)

    # ------------------------------------------------------------------ state
    @property
    def estopped(self) -> bool:
        return self._estopped

    @property
    def idle(self) -> bool:
        """Nothing to play; but samples must keep flowing while an e-stop ramps down and
        opens relays (a fast-forward driver only pulls while this is False)."""
        if not self._safe.is_set() or self.level_v != (0.0, 0.0):
            return False
        src = self._source
        if self._estopped or src is None:
            return True
        try:
            return bool(src.idle)
        except Exception:
            return False

    def attach(self, source: Source) -> None:
        """Play from ``source``: every block it gives passes the same checks as a plan's,
        and it runs on a guarded thread (a stall never holds the audio thread)."""
        with self._lock:
            self._source = source
            self._caller = SourceCaller("haptable-source")

    def attach_scheduler(self, scheduler: Source) -> None:
        """The output scheduler: core code that guards the plugin code it calls itself."""
        with self._lock:
            self._source = scheduler
            self._caller = None

    def quiet_samples(self) -> int:
        """How long both channels have been silent, in samples handed to the driver."""
        with self._lock:
            return self.clock - self._last_nonzero

    def settled(self) -> bool:
        """True once the settle time after the last relay switch has passed."""
        with self._lock:
            return self.clock >= self._quiet_until

    def relay_state(self) -> frozenset[int]:
        return frozenset(i + 1 for i, closed in enumerate(self.relays) if closed)

    def _max_steps(self) -> tuple[frozenset[str], float, float]:
        """The closed patches and each channel's slew step for the relays as they are:
        worked out once per relay state, not in every audio block."""
        relays = self.relays
        hit = self._steps_for
        if hit is None or hit[0] != relays:
            patches = self.closed_patches()
            lim = self.limits
            hit = (relays, patches, lim.max_step_v("piezo", patches), lim.max_step_v("screen"))
            self._steps_for = hit
        return hit[1], hit[2], hit[3]

    def closed_patches(self) -> frozenset[str]:
        relays = self.relays
        return frozenset(
            p
            for p, c in self.relay_channels.items()
            if p in PATCHES and 1 <= c <= len(relays) and relays[c - 1]
        )

    def _event(self, kind: str, message: str, *, cut: bool = True) -> None:
        ev = GateEvent(time.monotonic(), self.clock, kind, message, cut)
        self.events.append(ev)
        log.warning("%s: %s", kind, message) if kind in ("estop", "fault") else log.info(message)
        for fn in list(self.listeners):
            try:
                fn(ev)
            except Exception:  # a listener must never break the gate
                log.exception("gate listener failed")

    # ------------------------------------------------------------------ audio path
    def fill(self, out: np.ndarray) -> None:
        """Fill ``out`` (frames, 2) float32 in sound-card units. Called by the driver; never
        raises and never waits on plugin code longer than ``source_stall_s``."""
        self._audio_thread = threading.current_thread()
        try:
            self._fill(out)
        except Exception as exc:  # the audio thread must survive anything
            self._hand_ramp_down(out)
            self._fault(f"output path failed: {exc!r}")

    def _fill(self, out: np.ndarray) -> None:
        n = out.shape[0]
        with self._lock:
            src, caller = self._source, self._caller
            hold = self._estopped or self._switching
            clock = self.clock
        if hold or src is None:
            self._hand_ramp_down(out)
            return
        try:
            block = (
                src.next_block(n)
                if caller is None
                else caller.call(src.next_block, n, self.limits.source_stall_s)
            )
        except SourceInterrupted:
            block = None
        except Exception as exc:
            self._hand_ramp_down(out)
            self._fault(f"output source failed: {exc}")
            return
        if block is None:
            self._hand_ramp_down(out)
            return
        problem = None
        try:
            raw_p, raw_s = block
        except Exception:
            raw_p = raw_s = None
            problem = "output source gave no (piezo, screen) pair"
        piezo = screen = None
        if problem is None:
            piezo, problem = _as_volts(raw_p, n, "piezo")
        if problem is None:
            screen, problem = _as_volts(raw_s, n, "screen")
        if problem is None:
            problem = self._block_problem(piezo, screen, clock)
        if problem:
            self._hand_ramp_down(out)
            self._fault(problem)
            return
        with self._lock:
            if self._estopped or self._switching:  # e-stop or switch arrived meanwhile
                piezo = screen = None
        if piezo is None:
            self._hand_ramp_down(out)
            return
        self._hand(out, piezo, screen)

    def _hand(self, out: np.ndarray, piezo: np.ndarray, screen: np.ndarray) -> None:
        out[:, 0] = piezo * self._piezo_scale
        out[:, 1] = screen * self._screen_scale
        nz = bool(piezo.any() or screen.any())
        with self._lock:
            self.clock += out.shape[0]
            if nz:
                self._last_nonzero = self.clock
            self.level_v = (float(piezo[-1]), float(screen[-1]))

    def _hand_ramp_down(self, out: np.ndarray) -> None:
        """Hand the driver a ramp from the last level to zero at the slew limit (zeros
        once there): the only way the gate ever goes silent."""
        n = out.shape[0]
        lp, ls = self.level_v
        if lp == 0.0 and ls == 0.0:
            out[:] = 0.0
            with self._lock:
                self.clock += n
            return
        k = np.arange(1, n + 1)
        _, piezo_step, screen_step = self._max_steps()
        piezo, screen = (
            np.sign(level) * np.maximum(abs(level) - step * k, 0.0)
            for level, step in ((lp, piezo_step), (ls, screen_step))
        )
        self._hand(out, piezo, screen)

    def _block_problem(self, piezo: np.ndarray, screen: np.ndarray, clock: int) -> str | None:
        lim = self.limits
        for name, x, (lo, hi) in (
            ("piezo", piezo, lim.piezo_range()),
            ("screen", screen, lim.screen_range()),
        ):
            if (p := _range_problem(x, lo, hi, math.inf)) is not None:
                return f"{name} channel {p} of a block"
        p_on, s_on = bool(piezo.any()), bool(screen.any())
        if clock < self._quiet_until and (p_on or s_on):
            return "signal during the relay settle time"
        patches, piezo_step, screen_step = self._max_steps()
        if p_on and not patches:
            return "piezo signal while no patch relay is closed"
        relays = self.relays
        sc = self.screen_channel
        if s_on and sc is not None and not (1 <= sc <= len(relays) and relays[sc - 1]):
            return "screen signal while the screen relay is open"
        lp, ls = self.level_v
        for name, x, prev, step in (
            ("piezo", piezo, lp, piezo_step),
            ("screen", screen, ls, screen_step),
        ):
            if (p := _slew_problem(x, prev, step, end=False)) is not None:
                return f"{name} channel {p} (a block)"
        return None

    def _fault(self, message: str) -> None:
        self._event("fault", message)
        self.estop(
            f"fault: {message}",
            wait=threading.current_thread() is not self._audio_thread,
            cut=False,
        )

    # ------------------------------------------------------------------ relays
    def switch_wait_samples(self, closed: frozenset[int]) -> int:
        """Samples until every channel that would change may switch again (relay life)."""
        gap = self.limits.min_switch_interval_samples
        with self._lock:
            changing = [i + 1 for i, c in enumerate(self.relays) if c != (i + 1 in closed)]
            last = [self._last_switch.get(ch) for ch in changing]
            return max([0] + [t + gap - self.clock for t in last if t is not None])

    def switch_relays(self, closed: frozenset[int]) -> None:
        """Set the relay board to exactly ``closed`` (1-based channels), in silence.

        Raises ``SafetyRefusal`` when the samples handed to the driver have not been zero
        for the guard gap, when a channel switched less than ``min_switch_interval_ms``
        ago, when the e-stop is active (only opening is allowed then), or the driver fails.
        """
        board = self._board
        if board is None:
            if closed:
                raise SafetyRefusal("no relay board: cannot close relays")
            return
        n = len(self.relays)
        bad = [c for c in closed if not 1 <= c <= n]
        if bad:
            raise SafetyRefusal(f"relay channel {bad[0]} does not exist (board has {n})")
        with self._switch_lock:
            self._switch_held(board, closed, n)

    def _switch_held(self, board: RelayBoard, closed: frozenset[int], n: int) -> None:
        with self._lock:
            if self._estopped and closed:
                raise SafetyRefusal(
                    f"e-stop active ({self.estop_reason}): relays stay open; reset first"
                )
            if self._switching:
                raise SafetyRefusal("relay switch refused: another switch is under way")
            need = self.limits.guard_samples + self.latency_samples
            quiet = self.clock - self._last_nonzero
            if quiet < need or self.level_v != (0.0, 0.0):
                raise SafetyRefusal(
                    f"relay switch refused: outputs silent for {quiet} samples, "
                    f"need {need} (guard gap + device latency)"
                )
            wait = self.switch_wait_samples(closed)
            if wait > 0:
                fs = self.limits.sample_rate_hz
                raise SafetyRefusal(
                    f"relay switch refused: a channel switched "
                    f"{(self.limits.min_switch_interval_samples - wait) / fs * 1e3:.1f} ms ago; "
                    f"the rate limit allows one switch per "
                    f"{self.limits.min_switch_interval_samples / fs * 1e3:g} ms "
                    f"([relays] min_switch_interval_ms)"
                )
            self._switching = True
        try:
            target = tuple(i + 1 in closed for i in range(n))
            for i, (now, want) in enumerate(zip(self.relays, target, strict=True)):
                if now != want:
                    board.set(i + 1, want)
                    self._last_switch[i + 1] = self.clock
            self.relays = tuple(board.states())
            self._event("switch", f"relays closed: {sorted(closed) or 'none'}")
        except Exception as exc:
            with self._lock:
                self._switching = False
            self._fault(f"relay board failed: {exc!r}")
            raise SafetyRefusal(f"relay board failed: {exc}") from None
        with self._lock:
            self._quiet_until = self.clock + self.limits.settle_samples + self.latency_samples
            self._switching = False

    def _open_all_relays(self) -> None:
        board = self._board
        if board is None:
            return
        for ch in range(1, board.channels + 1):
            try:
                board.set(ch, False)
                self._last_switch[ch] = self.clock
            except Exception as exc:  # keep opening the others
                self._event("fault", f"relay {ch} failed to open: {exc!r}")
        try:
            self.relays = tuple(board.states())
        except Exception as exc:
            self._event("fault", f"relay board state unreadable: {exc!r}")

    # ------------------------------------------------------------------ e-stop
    def estop(
        self, reason: str = "e-stop", *, quiet: bool = False, wait: bool = True, cut: bool = True
    ) -> None:
        """Ramp to zero from the next block, drop the queue, then open every relay once
        the silence has been handed to the driver. Idempotent.

        ``quiet`` logs it as an ordinary shutdown (closing the outputs), not an alarm.
        ``wait=False`` (used from the audio thread) opens the relays on another thread.
        ``cut=False`` (a fault) lets the ramp down reach the amplifiers instead of inviting
        the driver to drop its queue.
        """
        with self._lock:
            first = not self._estopped
            self._estopped = True
            if first:
                self.estop_reason = reason
            src, caller = self._source, self._caller
            self._safe.clear()
        if caller is not None:
            caller.interrupt()
        if src is not None:
            try:
                src.abort(reason)
            except Exception:
                log.exception("source abort failed")
        if first:
            self._event("shutdown" if quiet else "estop", reason, cut=cut)
        if wait:
            self._open_when_silent()
        else:
            threading.Thread(
                target=self._open_when_silent, name="haptable-estop", daemon=True
            ).start()

    def _open_when_silent(self) -> None:
        """Wait for the driver to have been handed silence for the guard gap, then open
        every relay. A driver that stopped pulling (no clock for ``estop_timeout_ms``) is
        not playing anything: the relays open then too, and the event says so."""
        need = self.limits.guard_samples + self.latency_samples
        timeout = self.limits.estop_timeout_s
        last_clock, last_move = self.clock, time.monotonic()
        give_up = last_move + max(20 * timeout, 1.0)
        note = ""
        while True:
            with self._lock:
                silent = self.clock - self._last_nonzero >= need and self.level_v == (0.0, 0.0)
                clock = self.clock
            now = time.monotonic()
            if silent:
                break
            if clock != last_clock:
                last_clock, last_move = clock, now
            elif now - last_move > timeout:
                note = "the audio driver stopped pulling samples"
                break
            if now > give_up:
                note = "no silence reached the driver in time"
                break
            time.sleep(0.0005)
        if note:
            self._event("fault", f"relays opened without observed silence: {note}")
        with self._switch_lock:
            with self._lock:
                self._switching = True
            try:
                self._open_all_relays()
            finally:
                with self._lock:
                    self._switching = False
                    self._quiet_until = self.clock + self.limits.settle_samples
                self._safe.set()

    def wait_safe(self, timeout_s: float = 5.0) -> bool:
        """Block until an e-stop has opened the relays; True if it did in time."""
        return self._safe.wait(timeout_s)

    def reset(self) -> None:
        """Clear the e-stop (an operator action). Relays stay open until a plan asks."""
        with self._lock:
            if not self._estopped:
                return
            self._estopped = False
            self._event("reset", f"e-stop cleared (was: {self.estop_reason})")
            self.estop_reason = ""

    def status(self) -> dict[str, Any]:
        return {
            "estopped": self._estopped,
            "estop_reason": self.estop_reason,
            "clock": self.clock,
            "level_v": self.level_v,
            "relays_closed": sorted(self.relay_state()),
            "quiet_samples": self.quiet_samples(),
        }


# ---------------------------------------------------------------------- emergency hooks
_installed = False


def estop_all(reason: str) -> None:
    for gate in list(_LIVE_GATES):
        try:
            gate.estop(reason)
        except Exception:
            log.exception("e-stop failed")


def install_emergency_hooks() -> None:
    """E-stop every live gate on exit, SIGINT/SIGTERM and any unhandled exception."""
    global _installed
    if _installed:
        return
    _installed = True
    atexit.register(estop_all, "exit")

    prev_excepthook = sys.excepthook

    def excepthook(tp, value, tb):
        estop_all(f"unhandled exception: {tp.__name__}: {value}")
        prev_excepthook(tp, value, tb)

    sys.excepthook = excepthook
    prev_thread_hook = threading.excepthook

    def thread_hook(args):
        estop_all(
            f"unhandled exception in thread {args.thread.name if args.thread else '?'}: "
            f"{args.exc_type.__name__}: {args.exc_value}"
        )
        prev_thread_hook(args)

    threading.excepthook = thread_hook

    if threading.current_thread() is not threading.main_thread():
        return
    for sig in (signal.SIGINT, signal.SIGTERM):
        prev = signal.getsignal(sig)

        def handler(signum, frame, _prev=prev):
            estop_all(f"signal {signal.Signals(signum).name}")
            if callable(_prev):
                _prev(signum, frame)
            elif signum == signal.SIGINT:
                raise KeyboardInterrupt
            else:
                raise SystemExit(128 + signum)

        signal.signal(sig, handler)
