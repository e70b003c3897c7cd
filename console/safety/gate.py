"""The safety gate: every audio block on its way to the driver and every relay switch.

See ``console.safety`` for the rules it keeps. The gate is sealed: code holding it reads
its state through read-only properties and changes it only through its methods (an
attribute assignment raises ``AttributeError``); its limits, relay map and screen relay
channel are fixed when it is built."""

from __future__ import annotations

import logging
import threading
import time
import weakref
from collections.abc import Callable, Mapping
from types import MappingProxyType
from typing import Any, NoReturn

import numpy as np

from console.core.channels import ChannelLayout
from console.core.contracts import RelayBoard
from console.core.errors import SafetyRefusal
from console.core.types import PATCHES
from console.safety.block_rules import (
    GENERIC_REFUSAL,
    Judged,
    as_volts,
    block_first_problem,
    block_ok,
    block_problem,
    block_rules,
    read_only,
)
from console.safety.gate_state import GateEvent, GateState, ScopeView
from console.safety.limits import Limits
from console.safety.scope import ScopeTap
from console.safety.sources import Source

log = logging.getLogger("haptable.safety")


#: every gate alive in this process (what ``estop_all`` reaches)
LIVE_GATES: weakref.WeakSet[SafetyGate] = weakref.WeakSet()

#: events that carry the ramp-down step
_RAMP_KINDS = frozenset({"estop", "shutdown", "fault"})


class SafetyGate:
    """Owns the relay board, checks every block, and holds the e-stop.

    ``fill(out)`` is what the audio driver calls; it plays from the scheduler attached with
    ``attach_scheduler`` (the only source). Only the gate ever calls ``board.set``.

    Sealed: every attribute is read-only (``AttributeError`` on assignment or deletion).
    The limits, relay map and screen relay channel are fixed at construction; the device
    latency is raised once with ``set_device_latency``; listeners come and go with
    ``add_listener`` / ``remove_listener``.
    """

    __slots__ = (
        "__weakref__",
        "_board",
        "_events_lock",
        "_layout",
        "_limits",
        "_lock",
        "_rules",
        "_relay_channels",
        "_s",
        "_safe",
        "_scale",
        "_scope",
        "_scope_view",
        "_screen_channel",
        "_switch_lock",
    )

    def __init__(
        self,
        limits: Limits,
        board: RelayBoard | None,
        *,
        relay_channels: Mapping[str, int] | None = None,
        screen_channel: int | None = None,
        latency_samples: int = 0,
    ) -> None:
        if not isinstance(limits, Limits):
            raise TypeError(f"limits must be a Limits, not {type(limits).__name__}")
        latency = int(latency_samples)
        if latency < 0:
            raise ValueError(f"latency_samples = {latency_samples!r}: must be >= 0")
        layout = limits.layout  # what each sound-card channel drives
        names = layout.names
        card_v = tuple(
            limits.screen_card_v if kind == "screen" else limits.piezo_card_v
            for kind in layout.kinds()
        )
        scope = ScopeTap(limits.sample_rate_hz, names, card_v)
        init = object.__setattr__  # the one way in: __setattr__ refuses everyone
        init(self, "_limits", limits)
        init(self, "_board", board)
        init(
            self,
            "_relay_channels",
            MappingProxyType({str(p): int(c) for p, c in dict(relay_channels or {}).items()}),
        )
        init(self, "_screen_channel", None if screen_channel is None else int(screen_channel))
        init(self, "_layout", layout)
        init(self, "_rules", block_rules(limits))
        init(self, "_scale", read_only(1.0 / np.array(card_v)))
        #: the last seconds handed to the driver, per sound-card channel (``scope.read``)
        init(self, "_scope", scope)
        init(self, "_scope_view", ScopeView(scope))
        init(self, "_lock", threading.RLock())
        # held across a relay switch: an e-stop opening the relays waits for a switch in
        # flight to finish, so a late command can never close a relay after the e-stop
        init(self, "_switch_lock", threading.RLock())
        init(self, "_events_lock", threading.Lock())
        safe = threading.Event()
        safe.set()
        init(self, "_safe", safe)
        init(self, "_s", GateState(len(names), tuple(board.states()) if board else (), latency))
        LIVE_GATES.add(self)

    def __setattr__(self, name: str, value: Any) -> NoReturn:
        raise AttributeError(
            f"the safety gate is sealed: {name!r} cannot be set (its state changes only "
            f"through its own methods)"
        )

    def __delattr__(self, name: str) -> NoReturn:
        raise AttributeError(f"the safety gate is sealed: {name!r} cannot be deleted")

    # ------------------------------------------------------------------ read-only state
    @property
    def limits(self) -> Limits:
        """The limits every block is checked against (deep-immutable, fixed)."""
        return self._limits

    @property
    def relay_channels(self) -> Mapping[str, int]:
        """Patch -> relay channel (read-only, fixed at construction)."""
        return self._relay_channels

    @property
    def screen_channel(self) -> int | None:
        """The screen's relay channel (fixed at construction)."""
        return self._screen_channel

    @property
    def latency_samples(self) -> int:
        """The device latency in samples (raised once by ``set_device_latency``)."""
        return self._s.latency_samples

    @property
    def clock(self) -> int:
        """Samples handed to the driver."""
        return self._s.clock

    @property
    def level_v(self) -> tuple[float, ...]:
        """The last sample handed out per channel, volts at the actuators."""
        return self._s.level_v

    @property
    def relays(self) -> tuple[bool, ...]:
        """Each relay channel's state as the board last reported it (closed: True)."""
        return self._s.relays

    @property
    def events(self) -> tuple[GateEvent, ...]:
        """The last (up to 1000) events, oldest first: a snapshot."""
        with self._events_lock:
            return tuple(self._s.events)

    @property
    def layout(self) -> ChannelLayout:
        """What each sound-card channel drives."""
        return self._layout

    @property
    def estop_reason(self) -> str:
        return self._s.estop_reason

    @property
    def scope(self) -> ScopeView:
        """The last seconds handed to the driver, per sound-card channel (read-only)."""
        return self._scope_view

    @property
    def estopped(self) -> bool:
        return self._s.estopped

    @property
    def idle(self) -> bool:
        """Nothing to play; but samples must keep flowing while an e-stop ramps down and
        opens relays (a fast-forward driver only pulls while this is False)."""
        s = self._s
        if not self._safe.is_set() or any(s.level_v):
            return False
        src = s.source
        if s.estopped or src is None:
            return True
        try:
            return bool(src.idle)
        except Exception:
            return False

    # ------------------------------------------------------------------ set-up
    def attach_scheduler(self, scheduler: Source) -> None:
        """Play from the output scheduler (the only source): core code that guards the
        plugin code it calls itself. Every block it gives is checked."""
        with self._lock:
            self._s.source = scheduler

    def set_device_latency(self, samples: int) -> None:
        """The device latency, known once the driver started: set once, never lowered,
        only while nothing plays. Raises ``SafetyRefusal`` otherwise."""
        value = int(samples)
        if value < 0:
            raise ValueError(f"device latency {samples!r}: must be >= 0 samples")
        if not self.idle:  # outside the lock: the source's ``idle`` takes its own
            raise SafetyRefusal("the device latency is set only while nothing plays")
        s = self._s
        with self._lock:
            if s.latency_fixed:
                raise SafetyRefusal(
                    f"the device latency is already set ({s.latency_samples} samples)"
                )
            if value < s.latency_samples:
                raise SafetyRefusal(
                    f"device latency {value} samples is below the {s.latency_samples} the "
                    f"gate was built with; it can only be raised"
                )
            if any(s.level_v) or s.switching:
                raise SafetyRefusal("the device latency is set only while nothing plays")
            s.latency_samples = value
            s.latency_fixed = True

    def note_refusal(self, message: str) -> None:
        """Keep a request the kernel refused (a plan, a relay switch) as a ``refused``
        event: it changes nothing but the event log."""
        self._event("refused", str(message)[:500])

    def add_listener(self, fn: Callable[[GateEvent], None]) -> None:
        """Call ``fn(event)`` on every event (on the thread that raised it; it must be
        quick and never raise: an exception is logged and ignored)."""
        with self._lock:
            if fn not in self._s.listeners:
                self._s.listeners = (*self._s.listeners, fn)

    def remove_listener(self, fn: Callable[[GateEvent], None]) -> None:
        """Stop calling ``fn`` (nothing happens when it was not added)."""
        with self._lock:
            self._s.listeners = tuple(f for f in self._s.listeners if f != fn)

    # ------------------------------------------------------------------ state
    def quiet_samples(self) -> int:
        """How long both channels have been silent, in samples handed to the driver."""
        with self._lock:
            return self._s.clock - self._s.last_nonzero

    def settled(self) -> bool:
        """True once the settle time after the last relay switch has passed."""
        with self._lock:
            return self._s.clock >= self._s.quiet_until

    def relay_state(self) -> frozenset[int]:
        return frozenset(i + 1 for i, closed in enumerate(self._s.relays) if closed)

    def closed_patches(self) -> frozenset[str]:
        """The patches an amplifier reaches now: relay closed, or (a patch with a channel
        of its own and no relay) always."""
        return self._closed_patches(self._s.relays)

    def ramp_steps_v(self) -> tuple[float, ...]:
        """Each sound-card channel's slew step (volts per sample) for the relays as they
        are now: what the gate ramps down with."""
        return tuple(float(x) for x in self._steps(self._s.relays)[1])

    def _closed_patches(self, relays: tuple[bool, ...]) -> frozenset[str]:
        closed = {
            p
            for p, c in self._relay_channels.items()
            if p in PATCHES and 1 <= c <= len(relays) and relays[c - 1]
        }
        if self._layout.independent:
            closed.update(p for p in self._layout.patch_index if p not in self._relay_channels)
        return frozenset(closed)

    def _steps(self, relays: tuple[bool, ...]) -> tuple[frozenset[str], np.ndarray]:
        """The connected patches and each channel's slew step for ``relays``: worked out
        once per relay state, not in every audio block."""
        s = self._s
        hit = s.steps_for
        if hit is None or hit[0] != relays:
            patches = self._closed_patches(relays)
            hit = (relays, patches, read_only(self._limits.column_steps_v(patches)))
            s.steps_for = hit
        return hit[1], hit[2]

    def _judge_state(
        self, relays: tuple[bool, ...], level_v: tuple[float, ...], quiet_until: int, clock: int
    ) -> Judged:
        """What a block starting at ``clock`` is judged on, for this state."""
        patches, steps = self._steps(relays)
        sc = self._screen_channel
        screen_open = sc is not None and not (1 <= sc <= len(relays) and relays[sc - 1])
        return Judged(clock, quiet_until, level_v, relays, patches, steps, screen_open)

    def _judged(self) -> Judged:
        """The gate's state now, for the next block (call with the lock held)."""
        s = self._s
        return self._judge_state(s.relays, s.level_v, s.quiet_until, s.clock)

    def _event(self, kind: str, message: str, *, cut: bool = True) -> None:
        s = self._s
        ramp = self.ramp_steps_v() if kind in _RAMP_KINDS else ()
        ev = GateEvent(time.monotonic(), s.clock, kind, message, cut, ramp)
        with self._events_lock:
            s.events.append(ev)
        log.warning("%s: %s", kind, message) if kind in ("estop", "fault") else log.info(message)
        for fn in s.listeners:
            try:
                fn(ev)
            except Exception:  # a listener must never break the gate
                log.exception("gate listener failed")

    # ------------------------------------------------------------------ audio path
    def fill(self, out: np.ndarray) -> None:
        """Fill ``out`` (frames, channels) float32 in sound-card units, one column per
        ``[audio] channels`` name. Called by the driver; never raises."""
        s = self._s
        s.audio_thread = threading.current_thread()
        if out.ndim != 2 or out.shape[1] != self._layout.n:
            out[...] = 0.0
            self._fault(
                f"the audio output gave a block of shape {out.shape}, but [audio] channels "
                f"names {self._layout.n} channels; open the device with that many"
            )
            return
        clock = s.clock  # of the block's first sample (only this thread moves it)
        s.in_fill = True
        try:
            self._fill(out)
        except Exception as exc:  # the audio thread must survive anything
            self._hand_ramp_down(out)
            self._fault(f"output path failed: {exc!r}")
        finally:
            s.in_fill = False
        try:
            self._scope.write(out, clock)  # what the driver got, as it got it
        except Exception:  # the scope is an observer: never the output's problem
            log.exception("scope tap failed")

    def _fill(self, out: np.ndarray) -> None:
        n = out.shape[0]
        s = self._s
        with self._lock:
            src = s.source
            hold = s.estopped or s.switching
        if hold or src is None:
            self._hand_ramp_down(out)
            return
        try:
            block = src.next_block(n)
        except Exception as exc:
            self._hand_ramp_down(out)
            self._fault(f"output source failed: {exc}")
            return
        if block is None:
            self._hand_ramp_down(out)
            return
        cols, problem = self._columns(block, n)
        if problem is not None:
            self._hand_ramp_down(out)
            self._fault(problem)
            return
        # judged and handed over under the lock: no switch, e-stop or settle time can
        # fall between the look at the state, the verdict and the samples going out
        with self._lock:
            if s.estopped or s.switching:  # e-stop or switch arrived meanwhile
                judged = None
            else:
                judged = self._judged()
                if block_ok(cols, judged, self._rules):
                    self._hand(out, cols)
                    return
        if judged is None:
            self._hand_ramp_down(out)
            return
        # refused: the message is looked for on the same snapshot, and never overrules
        problem = block_first_problem(cols, judged, self._rules) or GENERIC_REFUSAL
        self._hand_ramp_down(out)
        self._fault(problem)

    def _columns(self, block: Any, n: int) -> tuple[list[np.ndarray] | None, str | None]:
        """A source's block as one float array of ``n`` samples per channel, or why not:
        a block is a sequence of one array per channel (the bus: ``(piezo, screen)``)."""
        names = self._layout.names
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
            a, problem = as_volts(x, n, name)
            if problem is not None:
                return None, problem
            cols.append(a)
        return cols, None

    def _hand(self, out: np.ndarray, cols: list[np.ndarray]) -> None:
        nz = False
        scale = self._scale
        for k, x in enumerate(cols):
            out[:, k] = x * scale[k]
            nz = nz or bool(x.any())
        s = self._s
        with self._lock:
            s.clock += out.shape[0]
            if nz:
                s.last_nonzero = s.clock
            s.level_v = tuple(float(x[-1]) for x in cols)

    def _hand_ramp_down(self, out: np.ndarray) -> None:
        """Hand the driver a ramp from the last level to zero at the slew limit (zeros
        once there), every channel at once: the only way the gate ever goes silent."""
        n = out.shape[0]
        s = self._s
        levels = s.level_v
        if not any(levels) or len(levels) != out.shape[1]:
            out[:] = 0.0
            with self._lock:
                s.clock += n
            return
        k = np.arange(1, n + 1)
        _, steps = self._steps(s.relays)
        cols = [
            np.sign(level) * np.maximum(abs(level) - step * k, 0.0)
            for level, step in zip(levels, steps, strict=True)
        ]
        self._hand(out, cols)

    def _block_problem(self, cols: list[np.ndarray], judged: Judged) -> str | None:
        """Why the block must not play, or ``None`` (``block_rules.block_problem``)."""
        return block_problem(cols, judged, self._rules)

    def _fault(self, message: str) -> None:
        self._event("fault", message)
        self.estop(
            f"fault: {message}",
            wait=threading.current_thread() is not self._s.audio_thread,
            cut=False,
        )

    # ------------------------------------------------------------------ relays
    def switch_wait_samples(self, closed: frozenset[int]) -> int:
        """Samples until every channel that would change may switch again (relay life)."""
        gap = self._limits.min_switch_interval_samples
        s = self._s
        with self._lock:
            changing = [i + 1 for i, c in enumerate(s.relays) if c != (i + 1 in closed)]
            last = [s.last_switch.get(ch) for ch in changing]
            return max([0] + [t + gap - s.clock for t in last if t is not None])

    def switch_relays(self, closed: frozenset[int]) -> None:
        """Set the relay board to exactly ``closed`` (1-based channels), in silence.

        Raises ``SafetyRefusal`` when the samples handed to the driver have not been zero
        for the guard gap, when a channel switched less than ``min_switch_interval_ms``
        ago, when the e-stop is active (only opening is allowed then), or the driver fails.
        """
        board = self._board
        closed = frozenset(closed)
        if board is None:
            if closed:
                raise SafetyRefusal("no relay board: cannot close relays")
            return
        n = len(self._s.relays)
        bad = [c for c in closed if not 1 <= c <= n]
        if bad:
            raise SafetyRefusal(f"relay channel {bad[0]} does not exist (board has {n})")
        with self._switch_lock:
            self._switch_held(board, closed, n)

    def _switch_held(self, board: RelayBoard, closed: frozenset[int], n: int) -> None:
        s, lim = self._s, self._limits
        with self._lock:
            if s.estopped and closed:
                raise SafetyRefusal(
                    f"e-stop active ({s.estop_reason}): relays stay open; reset first"
                )
            if s.switching:
                raise SafetyRefusal("relay switch refused: another switch is under way")
            need = lim.guard_samples + s.latency_samples
            quiet = s.clock - s.last_nonzero
            if quiet < need or any(s.level_v):
                raise SafetyRefusal(
                    f"relay switch refused: outputs silent for {quiet} samples, "
                    f"need {need} (guard gap + device latency)"
                )
            wait = self.switch_wait_samples(closed)
            if wait > 0:
                fs = lim.sample_rate_hz
                raise SafetyRefusal(
                    f"relay switch refused: a channel switched "
                    f"{(lim.min_switch_interval_samples - wait) / fs * 1e3:.1f} ms ago; "
                    f"the rate limit allows one switch per "
                    f"{lim.min_switch_interval_samples / fs * 1e3:g} ms "
                    f"([relays] min_switch_interval_ms)"
                )
            s.switching = True
        try:
            target = tuple(i + 1 in closed for i in range(n))
            for i, (now, want) in enumerate(zip(s.relays, target, strict=True)):
                if now != want:
                    board.set(i + 1, want)
                    s.last_switch[i + 1] = s.clock
            states = tuple(bool(c) for c in board.states())
            with self._lock:
                s.relays = states
            numbers = ",".join(str(c) for c in sorted(closed)) or "none"
            self._event("switch", f"relays closed: {numbers}")
        except Exception as exc:
            with self._lock:
                s.switching = False
            self._fault(f"relay board failed: {exc!r}")
            raise SafetyRefusal(f"relay board failed: {exc}") from None
        with self._lock:
            s.quiet_until = s.clock + lim.settle_samples + s.latency_samples
            s.switching = False

    def _open_all_relays(self) -> None:
        board = self._board
        if board is None:
            return
        s = self._s
        for ch in range(1, board.channels + 1):
            try:
                board.set(ch, False)
                s.last_switch[ch] = s.clock
            except Exception as exc:  # keep opening the others
                self._event("fault", f"relay {ch} failed to open: {exc!r}")
        try:
            states = tuple(bool(c) for c in board.states())
            with self._lock:
                was, s.relays = s.relays, states
            if was != states:  # a relay switch like any other: an event on every driver
                closed = ",".join(str(i + 1) for i, c in enumerate(states) if c) or "none"
                self._event("switch", f"relays opened by the e-stop; closed: {closed}")
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
        s = self._s
        with self._lock:
            first = not s.estopped
            s.estopped = True
            if first:
                s.estop_reason = str(reason)
            src = s.source
            self._safe.clear()
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
        on its source) has not stopped: its block may still be signal, so the wait goes on
        (at most the give-up time)."""
        s, lim = self._s, self._limits
        need = lim.guard_samples + s.latency_samples
        timeout = lim.estop_timeout_s
        last_clock, last_move = s.clock, time.monotonic()
        give_up = last_move + max(20 * timeout, 1.0)
        note = ""
        while True:
            with self._lock:
                silent = s.clock - s.last_nonzero >= need and not any(s.level_v)
                clock = s.clock
            now = time.monotonic()
            if silent:
                break
            if clock != last_clock or s.in_fill:
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
                s.switching = True
            try:
                self._open_all_relays()
            finally:
                with self._lock:
                    s.switching = False
                    s.quiet_until = s.clock + lim.settle_samples
                self._safe.set()

    def wait_safe(self, timeout_s: float = 5.0) -> bool:
        """Block until an e-stop has opened the relays; True if it did in time."""
        return self._safe.wait(timeout_s)

    def reset(self) -> None:
        """Clear the e-stop (an operator action). Relays stay open until a plan asks."""
        s = self._s
        with self._lock:
            if not s.estopped:
                return
            s.estopped = False
            self._event("reset", f"e-stop cleared (was: {s.estop_reason})")
            s.estop_reason = ""

    def status(self) -> dict[str, Any]:
        s = self._s
        return {
            "estopped": s.estopped,
            "estop_reason": s.estop_reason,
            "clock": s.clock,
            "level_v": s.level_v,
            "channels": list(self._layout.names),
            "relays_closed": sorted(self.relay_state()),
            "quiet_samples": self.quiet_samples(),
        }
