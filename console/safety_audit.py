"""What the amplifiers and relays received, checked against the gate's promises.

Used by the property tests and ``haptable bench safety`` on the twin's recording and
relay log: every sample inside the limits, no change faster than the slew limit (but at
a driver's cut for an operator's e-stop, where the device drops its queue), relays
switched only after the guard gap of silence, and silence within a block (plus the ramp
down) of every e-stop until the next reset.
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
    """Every broken promise in ``rec`` ((n, 2) volts) and ``relay_log`` since ``start``."""
    out: list[str] = []
    rec0, log0 = start.rec0, start.log0
    evs = [e for e in events if e.t_s >= start.t0_s]
    prev = rec[rec0 - 1] if rec0 > 0 else np.zeros(2)
    part = rec[rec0:]
    if not np.all(np.isfinite(part)):
        out.append("non-finite sample")
        return out
    lo, hi = limits.piezo_range()
    if part.size and (part[:, 0].min() < lo - 1e-4 or part[:, 0].max() > hi + 1e-4):
        out.append(f"piezo sample outside {lo:g}..{hi:g} V")
    if part.size and np.abs(part[:, 1]).max() > limits.screen_range()[1] + 1e-4:
        out.append("screen sample outside its limit")
    if part.shape[0]:
        steps = np.abs(np.diff(np.vstack([prev[None, :], part]), axis=0))
        ok = np.ones(steps.shape[0], bool)
        for e in evs:
            if e.kind in ("estop", "shutdown") and e.cut:
                i = e.clock - rec0
                ok[max(i - block, 0) : max(i + block, 0)] = False
        tol = 1.0005
        for ch, name, step in (
            (0, "piezo", limits.max_step_v("piezo", route)),
            (1, "screen", limits.max_step_v("screen")),
        ):
            worst = float(steps[ok, ch].max(initial=0.0))
            if worst > step * tol + 1e-4:
                k = rec0 + int(np.argmax(np.where(ok, steps[:, ch], 0.0)))
                out.append(f"{name} steps {worst:.2f} V at sample {k} (limit {step:.2f})")
    guard = limits.guard_samples
    for sw in relay_log[log0:]:
        if tuple(sw.level_v) != (0.0, 0.0):
            out.append(f"relay {sw.channel} switched at {sw.level_v} V")
        elif np.any(rec[max(rec0, sw.clock - guard) : sw.clock]):
            out.append(f"signal within the guard gap before relay {sw.channel} switched")
    ramp = int(np.ceil(hi / limits.max_step_v("piezo", route)))
    for i, e in enumerate(evs):
        if e.kind == "estop":
            resets = [r.clock for r in evs[i:] if r.kind == "reset"]
            after = rec[e.clock + block + ramp + 1 : resets[0] if resets else None]
            if np.any(after):
                out.append(f"not silent within a block of the e-stop at sample {e.clock}")
    return out
