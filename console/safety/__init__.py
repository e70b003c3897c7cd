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

The package in four modules: ``limits`` (the profile's limits and the plan check),
``sources`` (what the gate pulls from, plugin code kept off the audio thread), ``gate`` (the
per-block checks and relay switching) and ``emergency`` (e-stop of every live gate on exit,
signals and unhandled exceptions). Import from ``console.safety``.
"""

from console.safety.emergency import estop_all, install_emergency_hooks
from console.safety.gate import GateEvent, SafetyGate
from console.safety.limits import RAMP_TOLERANCE, Limits, check_plan
from console.safety.sources import Source, SourceCaller, SourceInterrupted, SourceStalled

__all__ = [
    "GateEvent",
    "Limits",
    "RAMP_TOLERANCE",
    "SafetyGate",
    "Source",
    "SourceCaller",
    "SourceInterrupted",
    "SourceStalled",
    "check_plan",
    "estop_all",
    "install_emergency_hooks",
]
