"""The safety gate: the only path from effects to the amplifiers and relays.

- Plans are checked before they play: over a limit, NaN/inf, a step faster than the slew
  limit anywhere, or not starting and ending at zero through a ramp -> refused with a
  message, never clipped. What plays is the private read-only copy that was checked.
- Every audio block, whatever produced it (a plan, a stream), is checked again on its
  way to the driver: finite numbers, limits, the slew limit against the last sample
  handed out, screen signal only with the screen relay closed. A bad block trips the
  e-stop and the driver gets a ramp to zero at the slew limit; a block the check fails
  is refused even when no single rule can be named for the message.
- The slew limit comes from the physics: the amplifier's peak current and the relay's
  current rating into the capacitance of the loads the relays connect (dV/dt = I / C).
- The gate plays from the output scheduler alone (``attach_scheduler``), inside the
  table's kernel process (``console.kernel``): no plugin code runs on the audio path (a
  live stream is synthesised there from its parameters).
- The gate is sealed: its limits (deep-immutable), relay map and screen relay channel are
  fixed when it is built, its state is read through read-only properties and changes
  only through its methods; an attribute assignment raises ``AttributeError``.
- Relays switch only while the samples handed to the driver have been zero for the guard
  gap (plus the device latency), at most once per ``[relays] min_switch_interval_ms`` per
  channel; the gate holds the outputs silent while a switch is under way and for the
  settle time after it, whatever a plugin asks.
- E-stop ramps the outputs to zero from the next audio block, then opens every relay once
  that silence has been handed to the driver. It is idempotent, and also runs on an
  unhandled exception, on SIGINT/SIGTERM and at exit of the kernel process; the kernel
  latches it (``console.kernel.tables``) until an operator resets it.

The package: ``limits`` (the profile's limits and the plan check), ``sources`` (what the
gate pulls from), ``gate`` (the per-block checks and relay switching), ``scope`` (the last
seconds handed to the driver) and ``emergency`` (e-stop of every live gate on exit,
signals and unhandled exceptions). Import from ``console.safety``.
"""

from console.safety.block_rules import GENERIC_REFUSAL
from console.safety.emergency import estop_all, install_emergency_hooks
from console.safety.gate import SafetyGate
from console.safety.gate_state import GateEvent, ScopeView
from console.safety.limits import RAMP_TOLERANCE, Limits, check_plan
from console.safety.sources import Source

__all__ = [
    "GENERIC_REFUSAL",
    "GateEvent",
    "Limits",
    "RAMP_TOLERANCE",
    "SafetyGate",
    "ScopeView",
    "Source",
    "check_plan",
    "estop_all",
    "install_emergency_hooks",
]
