"""The safety gate: the only path from effects to the amplifiers and relays.

- Plans are checked before they play: over a limit, NaN/inf, or not starting and ending at
  zero through a ramp -> refused with a message, never clipped.
- Every audio block is checked again on its way to the driver (last line of defence):
  a bad block trips the e-stop and the driver gets silence.
- Relays switch only while both channels have been silent for the guard gap (plus the
  device latency); the gate holds the outputs silent while a switch is under way and for
  the settle time after it, whatever a plugin asks.
- E-stop silences the outputs from the next audio block, then opens every relay. It is
  idempotent, and also runs on an unhandled exception, on SIGINT/SIGTERM and at exit.
"""

from __future__ import annotations

import atexit
import logging
import math
import signal
import sys
import threading
import time
import weakref
from collections import deque
from collections.abc import Callable
from dataclasses import dataclass
from typing import TYPE_CHECKING, Any

import numpy as np

from console.errors import SafetyRefusal
from console.types import PATCHES, OutputPlan, RelayBoard

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

    @classmethod
    def from_profile(cls, profile: Profile) -> Limits:
        fs = int(profile.get("audio.sample_rate_hz"))
        full = float(profile.get("audio.full_scale_v"))
        guard = profile.get("relays.guard_ms") * 1e-3
        switch = profile.get("relays.switch_time_ms") * 1e-3
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
        )

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
        for ch, (lo, hi) in (
            ("piezo_v", limits.piezo_range()),
            ("screen_v", limits.screen_range()),
        ):
            x = arrays[ch]
            if (p := _range_problem(x, lo, hi, limits.rating_vpp)) is not None:
                raise SafetyRefusal(f"{label}: {ch.split('_')[0]} channel {p}")
            if (p := _ramp_problem(x, limits.ramp_samples)) is not None:
                raise SafetyRefusal(f"{label}: {ch.split('_')[0]} channel {p}")
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


@dataclass(frozen=True)
class GateEvent:
    t_s: float
    clock: int
    kind: str  # "estop", "refused", "switch", "fault", "reset"
    message: str


_LIVE_GATES: weakref.WeakSet[SafetyGate] = weakref.WeakSet()


class SafetyGate:
    """Owns the relay board, checks every block, and holds the e-stop.

    ``fill(out)`` is what the audio driver calls. The scheduler is attached with
    ``attach(source)``. Only the gate ever calls ``board.set``.
    """

    def __init__(
        self,
        limits: Limits,
        board: RelayBoard | None,
        *,
        relay_channels: dict[str, int] | None = None,
        latency_samples: int = 0,
    ) -> None:
        self.limits = limits
        self._board = board
        self.relay_channels = dict(relay_channels or {})
        self.latency_samples = latency_samples
        self._lock = threading.RLock()
        self._source: Source | None = None
        self._estopped = False
        self.estop_reason = ""
        self._switching = False
        self.clock = 0  # samples handed to the driver
        self._last_nonzero = -(10**12)
        self._quiet_until = 0  # no signal before this clock (post-switch settle)
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
        """Nothing to play; but silence must keep flowing while an e-stop opens relays."""
        if not self._safe.is_set():
            return False
        src = self._source
        return self._estopped or src is None or src.idle

    def attach(self, source: Source) -> None:
        with self._lock:
            self._source = source

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

    def _event(self, kind: str, message: str) -> None:
        ev = GateEvent(time.monotonic(), self.clock, kind, message)
        self.events.append(ev)
        log.warning("%s: %s", kind, message) if kind in ("estop", "fault") else log.info(message)
        for fn in list(self.listeners):
            try:
                fn(ev)
            except Exception:  # a listener must never break the gate
                log.exception("gate listener failed")

    # ------------------------------------------------------------------ audio path
    def fill(self, out: np.ndarray) -> None:
        """Fill ``out`` (frames, 2) float32 in sound-card units. Called by the driver."""
        n = out.shape[0]
        with self._lock:
            src = self._source
            hold = self._estopped or self._switching
            clock = self.clock
        self._audio_thread = threading.current_thread()
        block = None
        if not hold and src is not None:
            try:
                block = src.next_block(n)
            except Exception as exc:
                self._fault(f"output source failed: {exc!r}")
                block = None
        if block is None:
            out[:] = 0.0
            self._advance(n, nonzero=False, last=(0.0, 0.0))
            return
        piezo, screen = block
        problem = self._block_problem(piezo, screen, n, clock)
        if problem:
            out[:] = 0.0
            self._fault(problem)
            self._advance(n, nonzero=False, last=(0.0, 0.0))
            return
        out[:, 0] = piezo * self._piezo_scale
        out[:, 1] = screen * self._screen_scale
        nz = bool(np.any(piezo) or np.any(screen))
        with self._lock:
            if self._estopped or self._switching:  # e-stop or switch arrived meanwhile
                out[:] = 0.0
                nz = False
        self._advance(n, nonzero=nz, last=(float(piezo[-1]), float(screen[-1])))

    def _block_problem(
        self, piezo: np.ndarray, screen: np.ndarray, n: int, clock: int
    ) -> str | None:
        if piezo.shape != (n,) or screen.shape != (n,):
            return f"output block has shape {piezo.shape}/{screen.shape}, expected ({n},)"
        lim = self.limits
        for name, x, (lo, hi) in (
            ("piezo", piezo, lim.piezo_range()),
            ("screen", screen, lim.screen_range()),
        ):
            if (p := _range_problem(x, lo, hi, math.inf)) is not None:
                return f"{name} channel {p} of a block"
        if clock < self._quiet_until and (np.any(piezo) or np.any(screen)):
            return "signal during the relay settle time"
        relays = self.relays
        if np.any(piezo) and not any(
            relays[c - 1]
            for p, c in self.relay_channels.items()
            if p in PATCHES and c <= len(relays)
        ):
            return "piezo signal while no patch relay is closed"
        return None

    def _advance(self, n: int, *, nonzero: bool, last: tuple[float, float]) -> None:
        with self._lock:
            self.clock += n
            if nonzero:
                self._last_nonzero = self.clock
            self.level_v = last

    def _fault(self, message: str) -> None:
        self._event("fault", message)
        self.estop(f"fault: {message}", wait=threading.current_thread() is not self._audio_thread)

    # ------------------------------------------------------------------ relays
    def switch_relays(self, closed: frozenset[int]) -> None:
        """Set the relay board to exactly ``closed`` (1-based channels), in silence.

        Raises ``SafetyRefusal`` when the outputs have not been silent for the guard
        gap, when the e-stop is active (only opening is allowed then), or the driver fails.
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
            self._switching = True
        try:
            target = tuple(i + 1 in closed for i in range(n))
            for i, (now, want) in enumerate(zip(self.relays, target, strict=True)):
                if now != want:
                    board.set(i + 1, want)
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
            except Exception as exc:  # keep opening the others
                self._event("fault", f"relay {ch} failed to open: {exc!r}")
        try:
            self.relays = tuple(board.states())
        except Exception as exc:
            self._event("fault", f"relay board state unreadable: {exc!r}")

    # ------------------------------------------------------------------ e-stop
    def estop(self, reason: str = "e-stop", *, quiet: bool = False, wait: bool = True) -> None:
        """Silence from the next block, drop the queue, then open every relay. Idempotent.

        ``quiet`` logs it as an ordinary shutdown (closing the outputs), not an alarm.
        ``wait=False`` (used from the audio thread) opens the relays on another thread.
        """
        with self._lock:
            first = not self._estopped
            self._estopped = True
            if first:
                self.estop_reason = reason
            src = self._source
            self._safe.clear()
        if src is not None:
            try:
                src.abort(reason)
            except Exception:
                log.exception("source abort failed")
        if first:
            self._event("shutdown" if quiet else "estop", reason)
        if wait:
            self._open_when_silent()
        else:
            threading.Thread(
                target=self._open_when_silent, name="haptable-estop", daemon=True
            ).start()

    def _open_when_silent(self) -> None:
        """Wait (bounded) for the silence to reach the relays, then open them all."""
        deadline = time.monotonic() + self.limits.estop_timeout_s
        need = self.limits.guard_samples + self.latency_samples
        while self.quiet_samples() < need and time.monotonic() < deadline:
            time.sleep(0.0005)
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
