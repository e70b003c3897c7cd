"""A designed signal as a plan for the gate: rendered at the profile's sample rate, on a
target (patches or the screen), checked against the limits before it plays.

The checks a designer hits first get their own words (the peak against the piezo range or
the screen's Vpp; the start and end ramps the gate asks for, with the ``ramp(...)`` that
fixes them; a step over the slew limit, with a ``lowpass(...)`` cutoff that smooths it);
then the gate's own ``check_plan`` runs on the very plan that will play. A
signal is never changed to pass: the operator adds the ramp to the expression.
"""

from __future__ import annotations

import math
from typing import Any

import numpy as np

from console.core.errors import SafetyRefusal
from console.core.types import OutputPlan
from console.safety import RAMP_TOLERANCE, Limits, check_plan
from console.signals.design import Node, Target, render, signal_plan
from console.signals.expr import parse


def ramp_hint(limits: Limits) -> str:
    ms = math.ceil(limits.ramp_samples / limits.sample_rate_hz * 1e3)
    return f"multiply it by ramp({ms} ms) (the profile's [limits] ramp_min_ms)"


def ramp_problem(x: np.ndarray, ramp: int) -> str | None:
    """Where ``x`` leaves the gate's linear start/end envelope of ``ramp`` samples."""
    peak = float(np.max(np.abs(x))) if x.size else 0.0
    if peak == 0.0:
        return None
    tol = 1e-6 * peak + 1e-9
    if abs(x[0]) > tol:
        return f"starts at {x[0]:.3g} V, not 0"
    if abs(x[-1]) > tol:
        return f"ends at {x[-1]:.3g} V, not 0"
    n = min(ramp, x.size)
    env = peak * (np.arange(n) / ramp) * RAMP_TOLERANCE + tol
    if np.any(np.abs(x[:n]) > env):
        return "rises faster than the gate's start ramp"
    if np.any(np.abs(x[::-1][:n]) > env):
        return "falls faster than the gate's end ramp"
    return None


def _nice_hz(f: float) -> str:
    """``f`` rounded down to 1, 2 or 5 times a power of ten, with its unit."""
    e = 10.0 ** math.floor(math.log10(max(f, 1.0)))
    nice = max(m * e for m in (1, 2, 5) if m * e <= max(f, 1.0))
    return f"{nice / 1e3:g} kHz" if nice >= 1e3 else f"{nice:g} Hz"


def slew_problem(x: np.ndarray, target: Target, limits: Limits) -> str | None:
    """The largest sample-to-sample step (from and back to 0 at the ends) when it is over
    the slew limit of the target's load, with a low-pass cutoff that brings a sine of the
    signal's peak within it (with a margin of two)."""
    chan = "screen" if target.screen else "piezo"
    step = limits.max_step_v(chan, target.patches)
    d = np.abs(np.diff(x, prepend=0.0, append=0.0))
    k = int(np.argmax(d))
    if d[k] <= step * (1 + 1e-9) + 1e-9:
        return None
    peak = float(np.max(np.abs(x)))
    cutoff = step * limits.sample_rate_hz / (2 * math.pi * peak) / 2
    return (
        f"steps {d[k]:.1f} V in one sample at {k / limits.sample_rate_hz:.4g} s, over the "
        f"slew limit of {step:.1f} V per sample into {target.label}; smooth its edges, "
        f"e.g. lowpass(..., {_nice_hz(cutoff)})"
    )


def range_source(channel: str, limits: Limits) -> str:
    """Where the gate's range for ``channel`` (``piezo``, ``screen``) comes from, as the
    operator checks it: the profile's ``[limits]``, and the card's full scale times the
    amplifier's gain where that is what holds it lower."""
    if channel == "screen":
        cap = f"[limits] screen_max_vpp = {2 * limits.screen_max_v:g} Vpp"
        card = limits.screen_card_v
        held = card < limits.screen_max_v
    else:
        cap = (
            f"[limits] piezo_min_v..piezo_max_v = {limits.piezo_min_v:g}..{limits.piezo_max_v:+g} V"
        )
        card = limits.piezo_card_v
        held = card < max(-limits.piezo_min_v, limits.piezo_max_v)
    if not held:
        return f"the profile's {cap}"
    return (
        f"the profile's {cap}, held to +-{card:g} V by what the sound card's full scale "
        "times the amplifier's gain can produce ([audio] full_scale_v, [amplifiers])"
    )


def level_problem(x: np.ndarray, target: Target, limits: Limits) -> str | None:
    """A peak beyond the gate's range for ``target``, with the range as the gate holds
    it and where it comes from (``range_source``)."""
    if target.screen:
        lo, hi = limits.screen_range()
        peak = float(np.max(np.abs(x)))
        if peak > hi + 1e-9:
            return (
                f"peak {peak:.1f} V ({2 * peak:.0f} Vpp) is beyond the screen's {2 * hi:g} Vpp "
                f"({range_source('screen', limits)}); lower the amplitude"
            )
        return None
    lo, hi = limits.piezo_range()
    mn, mx = float(np.min(x)), float(np.max(x))
    if mn < lo - 1e-9 or mx > hi + 1e-9:
        worst = mx if mx > hi + 1e-9 else mn
        return (
            f"peak {worst:.1f} V is beyond the piezo range {lo:g}..{hi:+g} V at the patch "
            f"({range_source('piezo', limits)}); lower the amplitude"
        )
    return None


def audition_plan(
    profile: Any, signal: str | Node, target: Target, name: str = "audition"
) -> OutputPlan:
    """``signal`` (an expression or a parsed node) as the plan that plays on ``target``;
    refused with one line (``SafetyRefusal``) before anything plays."""
    limits = Limits.from_profile(profile)
    node = parse(signal) if isinstance(signal, str) else signal
    fs = limits.sample_rate_hz
    x = render(node, fs, max_s=float(profile.get("limits.max_plan_s")), what=name)
    where = target.label
    if (p := level_problem(x, target, limits)) is not None:
        raise SafetyRefusal(f"{name} on {where}: {p}")
    if (p := ramp_problem(x, limits.ramp_samples)) is not None:
        raise SafetyRefusal(f"{name} on {where}: {p}; {ramp_hint(limits)}")
    if (p := slew_problem(x, target, limits)) is not None:
        raise SafetyRefusal(f"{name} on {where}: {p}")
    plan = signal_plan(x, target, fs, name)
    check_plan(plan, limits)
    return plan
