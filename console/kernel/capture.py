"""Play a plan through the gate and get what the sound card's inputs read meanwhile.

``capture(outputs, plan)`` plays ``plan`` as any client does (checked, then through the
gate: a plan over the limits is refused before a sample plays) and then asks the kernel
for the input channels from the plan's first sample to its last plus ``tail_s`` (the
``inputs`` request, ``console.kernel.input_requests``). ``move_sensor`` places the twin's
roving sensor (the operator's move, simulated; refused on a real table);
``inject_twin_faults`` breaks the twin as ``[twin_faults]`` would (tests, benches).
"""

from __future__ import annotations

import time
from dataclasses import dataclass
from typing import Any

import numpy as np

from console.core.audio_inputs import InputSpec
from console.core.errors import SafetyRefusal


@dataclass(frozen=True)
class Capture:
    """What the inputs read: ``card`` (n, inputs) in card units from ``clock`` on."""

    card: np.ndarray
    clock: int  # the gate's clock of row 0 (the plan's first sample)
    sample_rate_hz: int
    specs: tuple[InputSpec, ...]

    def physical(self, name_or_kind: str) -> np.ndarray:
        """One input in its unit (m/s^2, Pa, V): by name, else the first of that kind."""
        for i, s in enumerate(self.specs):
            if name_or_kind in (s.name, s.kind):
                return self.card[:, i].astype(np.float64) * s.scale()
        have = ", ".join(f"{s.name} ({s.kind})" for s in self.specs) or "none"
        raise SafetyRefusal(f"no input {name_or_kind!r} on this sound card (it has: {have})")


def read_inputs(outputs: Any, a: int, b: int, *, timeout_s: float = 30.0) -> Capture:
    """The inputs over clocks ``a..b``, once the outputs have played them."""
    deadline = time.monotonic() + timeout_s
    while True:
        h, arrays = outputs._call("inputs", a=int(a), b=int(b), timeout_s=timeout_s)
        specs = tuple(InputSpec.from_json(d) for d in h.get("specs") or ())
        if h.get("ready"):
            return Capture(arrays[0], int(a), int(outputs.limits.sample_rate_hz), specs)
        if time.monotonic() > deadline:
            raise SafetyRefusal(f"inputs: clock {b} not played within {timeout_s:g} s")
        fs = float(outputs.limits.sample_rate_hz)
        time.sleep(min(0.2, max(0.002, (b - int(h.get("clock", 0))) / fs)))


def capture(outputs: Any, plan: Any, *, tail_s: float = 0.0) -> Capture:
    """Play ``plan`` through the gate, then the inputs from its first sample to its last
    plus ``tail_s`` (``SafetyRefusal``: refused or stopped, one line). A fast-forward
    twin's clock stops when nothing plays: end the plan with the silence to record."""
    report = outputs.play(plan, wait=True)
    if not report.segment_start:
        raise SafetyRefusal(f"{plan.name or 'plan'}: played no sample")
    fs = int(outputs.limits.sample_rate_hz)
    a = int(report.segment_start[0])
    b = int(report.segment_end[-1]) + int(round(tail_s * fs))  # (end: exclusive)
    return read_inputs(outputs, a, b, timeout_s=tail_s + 30.0)


def move_sensor(outputs: Any, x_mm: float, y_mm: float, mass_g: float | None = None) -> dict:
    """Put the twin's roving sensor at (x_mm, y_mm) (and set its mass): its status."""
    h, _ = outputs._call("sensor", x_mm=float(x_mm), y_mm=float(y_mm), mass_g=mass_g)
    return {k: v for k, v in h.items() if k not in ("op", "id", "ok")}


def inject_twin_faults(outputs: Any, faults: dict) -> None:
    """The twin's faults from now on, as ``[twin_faults]`` keys (``{}``: healthy again)."""
    outputs._call("twin_faults", faults=dict(faults))
