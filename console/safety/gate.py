"""The safety gate: every audio block on its way to the driver and every relay switch.

See ``console.safety`` for the rules it keeps."""

from __future__ import annotations

import logging
import math
import threading
import time
import weakref
from collections import deque
from collections.abc import Callable
from dataclasses import dataclass
from typing import TYPE_CHECKING, Any

import numpy as np

from console.contracts import RelayBoard
from console.errors import SafetyRefusal
from console.safety.limits import Limits, range_problem, slew_problem
from console.safety.scope import ScopeTap
from console.safety.sources import Source, SourceCaller, SourceInterrupted
from console.types import PATCHES

if TYPE_CHECKING:
    pass

log = logging.getLogger("haptable.safety")


@dataclass(frozen=True)
class GateEvent:
    t_s: float
    clock: int
    kind: str  # "estop", "refused", "switch", "fault", "reset"
    message: str
    #: an e-stop a driver may answer by dropping its queued blocks at once (an operator's),
    #: and then every block until the gate hands one ending in silence (the rest of its
    #: ramp down, played after the drop, would step up from 0 V); a fault's e-stop is not
    #: cut: the gate's ramp to zero at the slew limit plays out
    cut: bool = True


#: every gate alive in this process (what ``estop_all`` reaches)
LIVE_GATES: weakref.WeakSet[SafetyGate] = weakref.WeakSet()


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
        self.layout = limits.layout  # what each sound-card channel drives
        names = self.layout.names
        #: the order the block checks look at the channels: piezo ones first
        self._check_order = sorted(range(len(names)), key=lambda k: names[k] == "screen")
        ranges = np.array(limits.column_ranges())
        self._ranges = (ranges[:, 0], ranges[:, 1])
        #: last sample handed out per channel, volts at the actuators
        self.level_v: tuple[float, ...] = (0.0,) * len(names)
        self.relays: tuple[bool, ...] = tuple(board.states()) if board else ()
        self.events: deque[GateEvent] = deque(maxlen=1000)
        self._safe = threading.Event()
        self._safe.set()
        self._audio_thread: threading.Thread | None = None
        #: the driver is inside ``fill`` (waiting on the gate: it has not stopped pulling)
        self._in_fill = False
        self.listeners: list[Callable[[GateEvent], None]] = []
        card_v = tuple(
            limits.screen_card_v if kind == "screen" else limits.piezo_card_v
            for kind in self.layout.kinds()
        )
        self._scale = 1.0 / np.array(card_v)
        #: the last seconds handed to the driver, per sound-card channel (``scope.read``)
        self.scope = ScopeTap(limits.sample_rate_hz, self.layout.names, card_v)
        LIVE_GATES.add(self)

    # ------------------------------------------------------------------ state
    @property
    def estopped(self) -> bool:
        return self._estopped

    @property
    def idle(self) -> bool:
        """Nothing to play; but samples must keep flowing while an e-stop ramps down and
        opens relays (a fast-forward driver only pulls while this is False)."""
        if not self._safe.is_set() or any(self.level_v):
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

    def _max_steps(self) -> tuple[frozenset[str], np.ndarray]:
        """The connected patches and each channel's slew step for the relays as they
        are: worked out once per relay state, not in every audio block."""
        relays = self.relays
        hit = self._steps_for
        if hit is None or hit[0] != relays:
            patches = self.closed_patches()
            hit = (relays, patches, self.limits.column_steps_v(patches))
            self._steps_for = hit
        return hit[1], hit[2]

    def closed_patches(self) -> frozenset[str]:
        """The patches an amplifier reaches now: relay closed, or (a patch with a channel
        of its own and no relay) always."""
        relays = self.relays
        closed = {
            p
            for p, c in self.relay_channels.items()
            if p in PATCHES and 1 <= c <= len(relays) and relays[c - 1]
        }
        if self.layout.independent:
            closed.update(p for p in self.layout.patch_index if p not in self.relay_channels)
        return frozenset(closed)

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
        """Fill ``out`` (frames, channels) float32 in sound-card units, one column per
        ``[audio] channels`` name. Called by the driver; never raises and never waits on
        plugin code longer than ``source_stall_s``."""
        self._audio_thread = threading.current_thread()
        if out.ndim != 2 or out.shape[1] != self.layout.n:
            out[...] = 0.0
            self._fault(
                f"the audio output gave a block of shape {out.shape}, but [audio] channels "
                f"names {self.layout.n} channels; open the device with that many"
            )
            return
        clock = self.clock  # of the block's first sample (only this thread moves it)
        self._in_fill = True
        try:
            self._fill(out)
        except Exception as exc:  # the audio thread must survive anything
            self._hand_ramp_down(out)
            self._fault(f"output path failed: {exc!r}")
        finally:
            self._in_fill = False
        try:
            self.scope.write(out, clock)  # what the driver got, as it got it
        except Exception:  # the scope is an observer: never the output's problem
            log.exception("scope tap failed")

    def _fill(self, out: np.ndarray) -> None:
        n = out.shape[0]
        with self._lock:
            src, caller = self._source, self._caller
            hold = self._estopped or self._switching
            clock = self.clock
            # an e-stop after this look interrupts the call below (estop() sets its flag
            # under this lock, then interrupts): none falls between the look and the call
            seen = caller.interrupts if caller is not None else 0
        if hold or src is None:
            self._hand_ramp_down(out)
            return
        try:
            block = (
                src.next_block(n)
                if caller is None
                else caller.call(src.next_block, n, self.limits.source_stall_s, since=seen)
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
        cols, problem = self._columns(block, n)
        if problem is None:
            problem = self._block_problem(cols, clock)
        if problem:
            self._hand_ramp_down(out)
            self._fault(problem)
            return
        with self._lock:
            if self._estopped or self._switching:  # e-stop or switch arrived meanwhile
                cols = None
        if cols is None:
            self._hand_ramp_down(out)
            return
        self._hand(out, cols)

    def _columns(self, block: Any, n: int) -> tuple[list[np.ndarray] | None, str | None]:
        """A source's block as one float array of ``n`` samples per channel, or why not:
        a block is a sequence of one array per channel (the bus: ``(piezo, screen)``)."""
        names = self.layout.names
        try:
            raw = tuple(block)
        except Exception:
            raw = ()
        if len(raw) != len(names):
            if len(names) == 2:
                return None, "output source gave no (piezo, screen) pair"
            return None, (
                f"output source gave {len(raw)} channels, expected {len(names)} "
                f"([audio] channels = {list(names)})"
            )
        cols = []
        for name, x in zip(names, raw, strict=True):
            a, problem = _as_volts(x, n, name)
            if problem is not None:
                return None, problem
            cols.append(a)
        return cols, None

    def _hand(self, out: np.ndarray, cols: list[np.ndarray]) -> None:
        nz = False
        for k, x in enumerate(cols):
            out[:, k] = x * self._scale[k]
            nz = nz or bool(x.any())
        with self._lock:
            self.clock += out.shape[0]
            if nz:
                self._last_nonzero = self.clock
            self.level_v = tuple(float(x[-1]) for x in cols)

    def _hand_ramp_down(self, out: np.ndarray) -> None:
        """Hand the driver a ramp from the last level to zero at the slew limit (zeros
        once there), every channel at once: the only way the gate ever goes silent."""
        n = out.shape[0]
        levels = self.level_v
        if not any(levels) or len(levels) != out.shape[1]:
            out[:] = 0.0
            with self._lock:
                self.clock += n
            return
        k = np.arange(1, n + 1)
        _, steps = self._max_steps()
        cols = [
            np.sign(level) * np.maximum(abs(level) - step * k, 0.0)
            for level, step in zip(levels, steps, strict=True)
        ]
        self._hand(out, cols)

    def _block_problem(self, cols: list[np.ndarray], clock: int) -> str | None:
        """Why the block must not play (the first rule it breaks), or ``None``. Every
        channel at once first (one pass over the block); only a block that fails is
        looked at channel by channel, for the message."""
        if self._block_ok(cols, clock):
            return None
        return self._block_first_problem(cols, clock)

    def _block_ok(self, cols: list[np.ndarray], clock: int) -> bool:
        """True when the block keeps every rule: finite, inside each channel's range, no
        signal while settling or on a channel whose load is disconnected, each step within
        its channel's slew limit (tolerances as in ``range_problem`` / ``slew_problem``)."""
        x = np.stack(cols)  # (channels, n)
        if x.shape[1] == 0:
            return True
        if not np.isfinite(x).all():
            return False
        lo, hi = self._ranges
        if (x.min(axis=1) < lo - 1e-9).any() or (x.max(axis=1) > hi + 1e-9).any():
            return False
        on = x.any(axis=1)
        if on.any():
            if clock < self._quiet_until:
                return False
            patches, _ = self._max_steps()
            for k in np.flatnonzero(on):
                name = self.layout.names[k]
                if name == "screen":
                    sc, relays = self.screen_channel, self.relays
                    if sc is not None and not (1 <= sc <= len(relays) and relays[sc - 1]):
                        return False
                elif (name == "piezo" and not patches) or (name != "piezo" and name not in patches):
                    return False
        _, steps = self._max_steps()
        d = np.abs(np.diff(x, axis=1, prepend=np.asarray(self.level_v)[:, None]))
        return bool((d.max(axis=1) <= steps * (1 + 1e-9) + 1e-9).all())

    def _block_first_problem(self, cols: list[np.ndarray], clock: int) -> str | None:
        lim = self.limits
        names = self.layout.names
        ranges = lim.column_ranges()
        for k in self._check_order:
            if (p := range_problem(cols[k], *ranges[k], math.inf)) is not None:
                return f"{names[k]} channel {p} of a block"
        on = [bool(x.any()) for x in cols]
        if clock < self._quiet_until and any(on):
            return "signal during the relay settle time"
        patches, steps = self._max_steps()
        for k in self._check_order:
            name = names[k]
            if not on[k] or name == "screen":
                continue
            if name == "piezo" and not patches:
                return "piezo signal while no patch relay is closed"
            if name != "piezo" and name not in patches:
                return f"{name} signal while its patch relay is open"
        relays = self.relays
        sc = self.screen_channel
        if (
            on[self.layout.screen_index]
            and sc is not None
            and not (1 <= sc <= len(relays) and relays[sc - 1])
        ):
            return "screen signal while the screen relay is open"
        for k in self._check_order:
            if (p := slew_problem(cols[k], self.level_v[k], steps[k], end=False)) is not None:
                return f"{names[k]} channel {p} (a block)"
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
            if quiet < need or any(self.level_v):
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
        not playing anything: the relays open then too, and the event says so. A driver
        inside ``fill`` (a block checked before the e-stop, its thread starved or waiting
        on a source) has not stopped: its block may still be signal, so the wait goes on
        (at most the give-up time)."""
        need = self.limits.guard_samples + self.latency_samples
        timeout = self.limits.estop_timeout_s
        last_clock, last_move = self.clock, time.monotonic()
        give_up = last_move + max(20 * timeout, 1.0)
        note = ""
        while True:
            with self._lock:
                silent = self.clock - self._last_nonzero >= need and not any(self.level_v)
                clock = self.clock
            now = time.monotonic()
            if silent:
                break
            if clock != last_clock or self._in_fill:
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
            "channels": list(self.layout.names),
            "relays_closed": sorted(self.relay_state()),
            "quiet_samples": self.quiet_samples(),
        }
