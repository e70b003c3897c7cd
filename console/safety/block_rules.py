"""The rules one output block is judged by: one pass over every channel, and, for a block
that fails, the first rule it breaks, worded (both on the same ``Judged`` state).

Plain functions of the block, the state read once for it and the gate's fixed
``BlockRules``; ``console.safety.gate`` calls them from the driver's ``fill``."""

from __future__ import annotations

import math
from typing import Any, NamedTuple

import numpy as np

from console.safety.limits import Limits, range_problem, slew_problem

#: the refusal when the one-pass check fails and the per-rule search names no rule
GENERIC_REFUSAL = "block refused by the gate's check (no single rule named)"


def as_volts(x: Any, n: int, name: str) -> tuple[np.ndarray | None, str | None]:
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


def read_only(a: Any) -> np.ndarray:
    """A float copy of ``a`` that cannot be written to."""
    out = np.array(a, dtype=np.float64)
    out.setflags(write=False)
    return out


class Judged(NamedTuple):
    """The state one block is judged on, read once: both checks look at this alone."""

    clock: int  # of the block's first sample
    quiet_until: int
    level_v: tuple[float, ...]
    relays: tuple[bool, ...]
    patches: frozenset[str]  # connected by ``relays``
    steps: np.ndarray  # each channel's slew step for ``relays`` (read-only)
    screen_relay_open: bool  # a screen relay channel is set and it is open


class BlockRules(NamedTuple):
    """What the checks need of the limits, fixed when the gate is built (read-only)."""

    names: tuple[str, ...]  # each sound-card channel's name
    lo: np.ndarray  # each channel's lowest volts
    hi: np.ndarray  # ... highest
    column_ranges: tuple[tuple[float, float], ...]
    check_order: tuple[int, ...]  # the order the channels are looked at: piezo ones first
    screen_index: int


def block_rules(limits: Limits) -> BlockRules:
    """The gate's ``BlockRules`` for ``limits``."""
    layout = limits.layout
    names = tuple(layout.names)
    ranges = np.array(limits.column_ranges())
    return BlockRules(
        names,
        read_only(ranges[:, 0]),
        read_only(ranges[:, 1]),
        tuple(limits.column_ranges()),
        tuple(sorted(range(len(names)), key=lambda k: names[k] == "screen")),
        layout.screen_index,
    )


def block_problem(cols: list[np.ndarray], j: Judged, rules: BlockRules) -> str | None:
    """Why the block must not play (the first rule it breaks), or ``None``. Every
    channel at once first (one pass over the block); only a block that fails is
    looked at channel by channel, for the message, on the same state; a failed block
    is refused whatever that search finds."""
    if block_ok(cols, j, rules):
        return None
    return block_first_problem(cols, j, rules) or GENERIC_REFUSAL


def block_ok(cols: list[np.ndarray], j: Judged, rules: BlockRules) -> bool:
    """True when the block keeps every rule: finite, inside each channel's range, no
    signal while settling or on a channel whose load is disconnected, each step within
    its channel's slew limit (tolerances as in ``range_problem`` / ``slew_problem``)."""
    x = np.stack(cols)  # (channels, n)
    if x.shape[1] == 0:
        return True
    if not np.isfinite(x).all():
        return False
    lo, hi = rules.lo, rules.hi
    if (x.min(axis=1) < lo - 1e-9).any() or (x.max(axis=1) > hi + 1e-9).any():
        return False
    on = x.any(axis=1)
    if on.any():
        if j.clock < j.quiet_until:
            return False
        names, patches = rules.names, j.patches
        for k in np.flatnonzero(on):
            name = names[k]
            if name == "screen":
                if j.screen_relay_open:
                    return False
            elif (name == "piezo" and not patches) or (name != "piezo" and name not in patches):
                return False
    d = np.abs(np.diff(x, axis=1, prepend=np.asarray(j.level_v)[:, None]))
    return bool((d.max(axis=1) <= j.steps * (1 + 1e-9) + 1e-9).all())


def block_first_problem(cols: list[np.ndarray], j: Judged, rules: BlockRules) -> str | None:
    """The first rule the block breaks, worded, judged on ``j`` (``None``: none found)."""
    names, ranges = rules.names, rules.column_ranges
    for k in rules.check_order:
        if (p := range_problem(cols[k], *ranges[k], math.inf)) is not None:
            return f"{names[k]} channel {p} of a block"
    on = [bool(x.any()) for x in cols]
    if j.clock < j.quiet_until and any(on):
        return "signal during the relay settle time"
    for k in rules.check_order:
        name = names[k]
        if not on[k] or name == "screen":
            continue
        if name == "piezo" and not j.patches:
            return "piezo signal while no patch relay is closed"
        if name != "piezo" and name not in j.patches:
            return f"{name} signal while its patch relay is open"
    if on[rules.screen_index] and j.screen_relay_open:
        return "screen signal while the screen relay is open"
    for k in rules.check_order:
        if (p := slew_problem(cols[k], j.level_v[k], j.steps[k], end=False)) is not None:
            return f"{names[k]} channel {p} (a block)"
    return None
