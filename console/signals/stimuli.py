"""Named test stimuli for ``haptable play NAME``: small, safe plans to check the chain."""

from __future__ import annotations

from collections.abc import Callable

import numpy as np

from console.core.errors import UserError
from console.core.suggest import suggestion
from console.core.types import PATCHES, OutputPlan, Segment, patches_of
from console.signals.waveforms import MAX_PLAN_S, check_duration, linear_chirp, tone


def _piezo(sig: np.ndarray, excitation: str, label: str) -> Segment:
    return Segment(sig, np.zeros_like(sig), patches_of(excitation), False, label)


def _sine_on(excitation: str) -> Callable[[int], OutputPlan]:
    def make(fs: int) -> OutputPlan:
        sig = tone(250.0, 20.0, 1.0, fs)
        return OutputPlan(
            fs, (_piezo(sig, excitation, f"250 Hz on {excitation}"),), name=f"sine-{excitation}"
        )

    return make


def _screen(fs: int) -> OutputPlan:
    sig = tone(180.0, 50.0, 1.0, fs)
    return OutputPlan(
        fs,
        (Segment(np.zeros_like(sig), sig, frozenset(), True, "180 Hz 100 Vpp"),),
        name="screen-180",
    )


def _sweep(fs: int) -> OutputPlan:
    sig = linear_chirp(10.0, 625.0, 10.0, 3.0, fs)
    return OutputPlan(fs, (_piezo(sig, "PALL", "10-625 Hz sweep"),), name="sweep")


def _relay_walk(fs: int) -> OutputPlan:
    segs = tuple(_piezo(tone(250.0, 10.0, 0.3, fs), e, e) for e in (*PATCHES, "PALL"))
    return OutputPlan(fs, segs, name="relay-walk", gap_s=0.05)


STIMULI: dict[str, tuple[str, Callable[[int], OutputPlan]]] = {
    **{f"sine-{e}": (f"250 Hz, 20 V peak, 1 s on {e}", _sine_on(e)) for e in (*PATCHES, "PALL")},
    "screen-180": ("180 Hz, 100 Vpp, 1 s on the screen (electrovibration)", _screen),
    "sweep": ("10-625 Hz linear sweep, 10 V peak, 3 s on all patches", _sweep),
    "relay-walk": (
        "250 Hz bursts on PA, PB, PC, PD, PALL in turn (relays switch between)",
        _relay_walk,
    ),
}


#: Each stimulus's length in seconds, checked against ``[limits] max_plan_s`` before
#: its arrays are built.
DURATION_S: dict[str, float] = {
    **{f"sine-{e}": 1.0 for e in (*PATCHES, "PALL")},
    "screen-180": 1.0,
    "sweep": 3.0,
    "relay-walk": 0.3 * (len(PATCHES) + 1),
}


#: Former names, still played (scripts and notes use them); each stimulus has one name,
#: the one listed, the signal library's where it has the same signal (``screen-180``,
#: ``sweep``; its ``tone-250`` is the ``sine-P..`` tone without a patch).
ALIASES: dict[str, str] = {"screen-180hz": "screen-180"}


def make_stimulus(name: str, fs: int, max_s: float = MAX_PLAN_S) -> OutputPlan:
    """The named stimulus at ``fs``, refused before it is built when longer than
    ``max_s`` (the profile's ``[limits] max_plan_s``)."""
    name = ALIASES.get(name, name)
    if name not in STIMULI:
        hint = suggestion(name, STIMULI, "did you mean {!r}? ")
        raise UserError(f"no test stimulus {name!r}; {hint}available: {', '.join(STIMULI)}")
    check_duration(DURATION_S[name], max_s, f"play {name}")
    return STIMULI[name][1](fs)
