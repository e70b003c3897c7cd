"""The outputs of a profile behind the safety gate: what commands and the console use.

``open_outputs(profile, plugins)`` builds the profile's audio output and relay board,
puts the safety gate between them and everything else, and starts the scheduler.
Nothing outside this module holds a driver.
"""

from __future__ import annotations

import logging
import sys
from typing import Any

import numpy as np

from console.contracts import SimulatedAudio, SimulatedRelays, StreamSource
from console.errors import SafetyRefusal, UserError
from console.runtime.outputs_registry import register_outputs
from console.runtime.scheduler import PlayReport, Scheduler
from console.safety import Limits, SafetyGate, install_emergency_hooks
from console.types import OutputPlan

log = logging.getLogger("haptable.outputs")


class Outputs:
    """Play plans and streams, switch relays, e-stop. Always through the gate."""

    registration = None  # until the outputs are registered (``haptable estop``)

    def __init__(self, profile, plugins, *, fast: bool | None = None):
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
        if fast is not None and simulated:
            audio.paced = not fast
        self._audio = audio
        self._board = board
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
        install_emergency_hooks()
        try:
            audio.start(self.gate)
        except Exception as exc:
            self.gate.estop("audio output failed to start")
            board.close()
            raise UserError(
                f"audio output {audio_reg.name!r} failed to start: {exc}; "
                f"run `haptable doctor` for the fix"
            ) from None
        lat = audio.status().get("latency_s") or 0.0
        self.gate.latency_samples = max(
            int(audio.block_size), int(round(lat * self.limits.sample_rate_hz))
        )
        paced = audio.paced if simulated else True
        if paced:  # the audio thread must get the GIL in time
            want_s = float(profile.get("audio.switch_interval_ms")) * 1e-3
            if sys.getswitchinterval() > want_s:
                sys.setswitchinterval(want_s)
        self.memory_locked, self.memory_note = False, "real-time memory lock not asked for"
        if profile.get("audio.lock_memory") and paced:
            from .memory_lock import lock_memory

            self.memory_locked, self.memory_note = lock_memory()
            if not self.memory_locked:
                log.warning("%s", self.memory_note)
        self._closed = False
        self.registration = register_outputs(self)  # `haptable estop` reaches this process

    # ------------------------------------------------------------------ playing
    def play(
        self, plan: OutputPlan, *, wait: bool = True, timeout_s: float | None = None
    ) -> PlayReport:
        """Check and play a plan; with ``wait`` return when it finished (or raise)."""
        report = self.scheduler.play(plan)
        if wait:
            report.wait(timeout_s if timeout_s is not None else 3 * plan.duration_s + 10)
            if report.error:
                raise SafetyRefusal(f"{report.name}: {report.error}")
        return report

    def precheck(self, plan: OutputPlan) -> None:
        """Check a plan ahead of playing it (a plan about to be asked for: its check is
        then not on the path to its first sample); ``SafetyRefusal`` if refused."""
        self.scheduler.precheck(plan)

    def prearm(self, patches: frozenset[str], screen: bool) -> PlayReport | None:
        """Close the relays of a plan's first segment ahead of it, in silence through the
        gate (only while nothing plays and the operator's relays are all open), so that
        the plan plays at the next block; ``None`` when not done. Non-blocking."""
        return self.scheduler.prearm(frozenset(patches), screen)

    def disarm(self) -> PlayReport | None:
        """Cancel a pre-arm: the relays open again in silence (a queued plan is left to
        open them when it ends). Non-blocking."""
        return self.scheduler.disarm()

    def stream(self, source: StreamSource, name: str = "stream") -> PlayReport:
        return self.scheduler.stream(source, name)

    def set_relays(
        self, closed: frozenset[int] | set[int], *, wait: bool = True, timeout_s: float = 5.0
    ) -> PlayReport:
        """The operator's relay setting: refused during an e-stop; with ``wait``, a command
        not done within ``timeout_s`` is dropped (never runs later) and refused."""
        report = self.scheduler.set_relays(frozenset(closed))
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

    # ------------------------------------------------------------------ twin recordings
    def recording(self) -> np.ndarray | None:
        """What the twin amplifiers received, (n, channels) volts (a column per ``[audio]
        channels`` name); ``None`` on real hardware."""
        audio = self._audio
        return audio.recording_v() if isinstance(audio, SimulatedAudio) else None

    def relay_log(self) -> list | None:
        """Every relay switch of the twin's board, in order; ``None`` on real hardware."""
        return self._board.log if isinstance(self._board, SimulatedRelays) else None

    def status(self) -> dict[str, Any]:
        return {
            "gate": self.gate.status(),
            "audio": self._audio.status(),
            "relays": self._board.status(),
            "busy": self.scheduler.busy,
            "memory_locked": self.memory_locked,
            "memory_note": self.memory_note,
        }

    def close(self) -> None:
        """Silence, open every relay, stop the audio device. Safe to call twice."""
        if self._closed:
            return
        self._closed = True
        try:
            self.gate.estop("outputs closed", quiet=True)
        finally:
            try:
                self._audio.stop()
            finally:
                self.scheduler.close()
                if self.registration is not None:
                    self.registration.close()
                try:
                    self._board.close()
                except Exception:
                    log.exception("relay board close failed")
                if self.memory_locked:
                    from .memory_lock import unlock_memory

                    unlock_memory()

    def __enter__(self) -> Outputs:
        return self

    def __exit__(self, *exc) -> None:
        self.close()


def open_outputs(profile, plugins, *, fast: bool | None = None) -> Outputs:
    return Outputs(profile, plugins, fast=fast)
