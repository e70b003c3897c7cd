"""A table's outputs in this process: the relay board and the audio output behind the
safety gate and the output scheduler. The kernel process (``console.kernel.server``) is
the one place they are built for real use; unit tests of the gate build them here too.

Built from the profile (``TableOutputs(profile, plugins)``): the relay board opens with
every relay opened, the audio output starts pulling from the gate (through a port that
can fill, report a device fault and listen, nothing more), the device latency goes into
the gate's guard and settle gaps, and paced outputs get the GIL switch interval and the
memory lock real-time audio needs. ``close()`` ramps to silence, opens every relay and
stops the audio.
"""

from __future__ import annotations

import contextlib
import gc
import logging
import math
import sys
from collections.abc import Callable
from typing import Any

import numpy as np

from console.core.contracts import SimulatedAudio, SimulatedRelays
from console.core.errors import SafetyRefusal, UserError
from console.kernel.duplex import attach_plate
from console.kernel.memory_lock import lock_memory, unlock_memory
from console.kernel.scheduler import CheckedPlan, PlayReport, Scheduler
from console.safety import Limits, SafetyGate

log = logging.getLogger("haptable.kernel")


class DriverPort:
    """What the audio driver gets instead of the gate: ``fill``, ``idle``, ``estop`` (a
    device fault), listeners and the ramp steps. Nothing to reset, nothing to set."""

    __slots__ = ("_gate",)

    def __init__(self, gate: SafetyGate) -> None:
        self._gate = gate

    def fill(self, out: np.ndarray) -> None:
        self._gate.fill(out)

    @property
    def idle(self) -> bool:
        return self._gate.idle

    def estop(self, reason: str, wait: bool = False, **_: Any) -> None:
        self._gate.estop(f"audio output: {reason}", wait=wait, cut=False)

    def add_listener(self, fn: Callable[[Any], None]) -> None:
        self._gate.add_listener(fn)

    def remove_listener(self, fn: Callable[[Any], None]) -> None:
        self._gate.remove_listener(fn)

    def ramp_steps_v(self) -> tuple[float, ...]:
        return self._gate.ramp_steps_v()


class TableOutputs:
    """The drivers, the gate and the scheduler of one table (see the module's doc).

    ``fast``: the twin fast-forward (not paced). ``twin_only``: refuse real drivers.
    ``before_start(gate)`` runs once the gate exists and before any sample is pulled
    (the kernel applies a latched e-stop there)."""

    def __init__(
        self,
        profile: Any,
        plugins: Any,
        *,
        fast: bool | None = None,
        twin_only: bool = False,
        before_start: Callable[[SafetyGate], None] | None = None,
    ) -> None:
        self.profile = profile
        self.limits = Limits.from_profile(profile)
        audio_reg = plugins.get("audio_output", profile.get("audio.driver"))
        relay_reg = plugins.get("relay_board", profile.get("relays.driver"))
        try:
            board = plugins.build("relay_board", relay_reg.name, profile)
        except UserError:
            raise
        except Exception as exc:
            raise UserError(
                f"relay board {relay_reg.name!r} failed to open: {exc}; "
                f"run `haptable doctor` for the fix"
            ) from None
        for ch in range(1, int(board.channels) + 1):  # whatever a dead kernel left closed
            with contextlib.suppress(Exception):
                board.set(ch, False)
        try:
            audio = plugins.build("audio_output", audio_reg.name, profile)
        except UserError:
            board.close()
            raise
        except Exception as exc:
            board.close()
            raise UserError(
                f"audio output {audio_reg.name!r} failed to open: {exc}; "
                f"run `haptable doctor` for the fix"
            ) from None
        simulated = isinstance(audio, SimulatedAudio)
        if twin_only and not (simulated and isinstance(board, SimulatedRelays)):
            board.close()
            raise UserError("a private table runs on the twin only ([audio] and [relays] driver)")
        if fast is not None and simulated:
            audio.paced = not fast
        attach_plate(audio, plugins, profile)  # a twin card's sensors read the plate
        self.audio, self.board = audio, board
        relay_channels = {
            n: int(p["relay_channel"])
            for n, p in profile.items("patches").items()
            if p.get("relay_channel")  # 0: no relay (a patch on a channel of its own)
        }
        screen_channel = int(profile.get("screen.relay_channel"))
        self.gate = SafetyGate(
            self.limits,
            board,
            relay_channels=relay_channels,
            screen_channel=screen_channel,
            latency_samples=int(audio.block_size),
        )
        self.scheduler = Scheduler(
            self.gate, relay_channels=relay_channels, screen_channel=screen_channel
        )
        if before_start is not None:
            before_start(self.gate)
        self.paced = audio.paced if simulated else True
        if self.paced:  # the audio thread must get the GIL in time
            want_s = float(profile.get("audio.switch_interval_ms")) * 1e-3
            if sys.getswitchinterval() > want_s:
                sys.setswitchinterval(want_s)
        # everything loaded so far (plugins, libraries) stays: a full garbage collection
        # walking it holds the interpreter for ~10 ms, the audio thread waiting for it;
        # frozen before the first sample, the collector only looks at what comes after
        gc.collect()
        gc.freeze()
        try:
            audio.start(DriverPort(self.gate))
        except Exception as exc:
            self.gate.estop("audio output failed to start")
            board.close()
            raise UserError(
                f"audio output {audio_reg.name!r} failed to start: {exc}; "
                f"run `haptable doctor` for the fix"
            ) from None
        lat = audio.status().get("latency_s") or 0.0
        if not (isinstance(lat, float) and math.isfinite(lat)):
            lat = 0.0
        self.gate.set_device_latency(
            max(int(audio.block_size), int(round(lat * self.limits.sample_rate_hz)))
        )
        self.memory_locked, self.memory_note = False, "real-time memory lock not asked for"
        if profile.get("audio.lock_memory") and self.paced:
            self.memory_locked, self.memory_note = lock_memory()
            if not self.memory_locked:
                log.warning("%s", self.memory_note)
        self._closed = False

    # ------------------------------------------------------------------ playing
    def check(self, plan: Any) -> CheckedPlan:
        """Check a plan against the limits (``SafetyRefusal``); its private copy."""
        return self.scheduler.check(plan)

    def play(
        self,
        plan: Any,
        *,
        wait: bool = True,
        timeout_s: float | None = None,
        owner: int = 0,
        on_change: Any = None,
    ) -> PlayReport:
        """Check and play a plan (a ``CheckedPlan`` plays as checked); with ``wait``
        return when it finished (or raise ``SafetyRefusal``)."""
        checked = plan if isinstance(plan, CheckedPlan) else self.check(plan)
        report = self.scheduler.play(checked, owner=owner, on_change=on_change)
        if wait:
            report.wait(timeout_s if timeout_s is not None else 3 * checked.duration_s + 10)
            if report.error:
                raise SafetyRefusal(f"{report.name}: {report.error}")
        return report

    def set_relays(
        self,
        closed: Any,
        *,
        wait: bool = True,
        timeout_s: float = 5.0,
        owner: int = 0,
        on_change: Any = None,
    ) -> PlayReport:
        """The operator's relay setting: refused during an e-stop; with ``wait``, a command
        not done within ``timeout_s`` is dropped (never runs later) and refused."""
        report = self.scheduler.set_relays(frozenset(closed), owner=owner, on_change=on_change)
        if wait:
            try:
                report.wait(timeout_s)
            except TimeoutError:
                why = f"relay command timed out after {timeout_s:g} s and was dropped"
                if self.scheduler.cancel(report, why):
                    raise SafetyRefusal(why) from None
                report.wait(timeout_s)  # it was switching at that moment: let it finish
            if report.error:
                raise SafetyRefusal(report.error)
        return report

    # ------------------------------------------------------------------ safety
    def estop(self, reason: str = "operator e-stop") -> None:
        self.gate.estop(reason)

    def reset(self) -> None:
        self.gate.reset()

    # ------------------------------------------------------------------ the twin
    def recording(self) -> np.ndarray | None:
        """What the twin amplifiers received, (n, channels) volts; None on hardware."""
        audio = self.audio
        return audio.recording_v() if isinstance(audio, SimulatedAudio) else None

    def relay_log(self) -> list | None:
        """Every relay switch of the twin's board, in order; None on real hardware."""
        return self.board.log if isinstance(self.board, SimulatedRelays) else None

    def status(self) -> dict[str, Any]:
        return {
            "gate": self.gate.status(),
            "audio": self.audio.status(),
            "relays": self.board.status(),
            "busy": self.scheduler.busy,
            "operator_relays": sorted(self.scheduler.operator_relays),
            "memory_locked": self.memory_locked,
            "memory_note": self.memory_note,
            "latency_samples": int(self.gate.latency_samples),
        }

    # ------------------------------------------------------------------ closing
    def close(self, reason: str = "outputs closed") -> None:
        """Silence, open every relay, stop the audio device. Safe to call twice."""
        if self._closed:
            return
        self._closed = True
        try:
            self.gate.estop(reason, quiet=True)
        finally:
            try:
                self.audio.stop()
            finally:
                self.scheduler.close()
                try:
                    self.board.close()
                except Exception:
                    log.exception("relay board close failed")
                if self.memory_locked:
                    unlock_memory()

    def __enter__(self) -> TableOutputs:
        return self

    def __exit__(self, *exc: Any) -> None:
        self.close()
