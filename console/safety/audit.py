"""What the amplifiers and relays received, checked against the gate's promises.

Used by the property tests and ``haptable bench safety`` on the twin's recording and
relay log: every sample inside the limits, no change faster than the slew limit anywhere
(an operator's e-stop ramps at the driver too: no exemption at a cut), relays switched
only after the guard gap of silence, and silence within a block (plus the ramp down) of
every e-stop until the next reset.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from console.safety import GateEvent, Limits


@dataclass(frozen=True)
class Window:
    """Where a check starts: the recording length, relay log length and the time then."""

    rec0: int
    log0: int
    t0_s: float


def received_problems(
    limits: Limits,
    rec: np.ndarray,
    relay_log: list,
    events: list[GateEvent],
    start: Window,
    route: frozenset[str],
    block: int,
) -> list[str]:
    """Every broken promise in ``rec`` ((n, channels) volts, a column per ``[audio]
    channels`` name) and ``relay_log`` since ``start``; ``route`` is the patches the bus
    reached (for its slew limit)."""
    out: list[str] = []
    rec0, log0 = start.rec0, start.log0
    names = limits.channels
    evs = [e for e in events if e.t_s >= start.t0_s]
    prev = rec[rec0 - 1] if rec0 > 0 else np.zeros(len(names))
    part = rec[rec0:]
    if not np.all(np.isfinite(part)):
        out.append("non-finite sample")
        return out
    for k, (name, (lo, hi)) in enumerate(zip(names, limits.column_ranges(), strict=True)):
        if not part.size:
            break
        if part[:, k].min() < lo - 1e-4 or part[:, k].max() > hi + 1e-4:
            if name == "screen":
                out.append("screen sample outside its limit")
            else:
                out.append(f"{name} sample outside {lo:g}..{hi:g} V")
    steps_v = limits.column_steps_v(route)
    if part.shape[0]:
        steps = np.abs(np.diff(np.vstack([prev[None, :], part]), axis=0))
        tol = 1.0005
        for ch, (name, step) in enumerate(zip(names, steps_v, strict=True)):
            worst = float(steps[:, ch].max(initial=0.0))
            if worst > step * tol + 1e-4:
                k = rec0 + int(np.argmax(steps[:, ch]))
                out.append(f"{name} steps {worst:.2f} V at sample {k} (limit {step:.2f})")
    guard = limits.guard_samples
    for sw in relay_log[log0:]:
        if any(sw.level_v):
            out.append(f"relay {sw.channel} switched at {sw.level_v} V")
        elif np.any(rec[max(rec0, sw.clock - guard) : sw.clock]):
            out.append(f"signal within the guard gap before relay {sw.channel} switched")
    hi = limits.piezo_range()[1]
    ramp = max(
        int(np.ceil(hi / step))
        for name, step in zip(names, steps_v, strict=True)
        if name != "screen"
    )
    for i, e in enumerate(evs):
        if e.kind == "estop":
            resets = [r.clock for r in evs[i:] if r.kind == "reset"]
            after = rec[e.clock + block + ramp + 1 : resets[0] if resets else None]
            if np.any(after):
                out.append(f"not silent within a block of the e-stop at sample {e.clock}")
    return out
