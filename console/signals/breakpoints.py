"""Breakpoint shapes for the signal syntax: what imported haptic files (AHAP, ``.haptic``)
become, usable in any expression.

- ``env(T1, L1, T2, L2, ...)``: a ratio envelope through the breakpoints (time, level),
  linear between them, as long as its last time; before the first time it holds L1.
  ``env(0 s, 0 %, 20 ms, 100 %, 0.5 s, 0 %)`` rises in 20 ms and falls to 0 at 0.5 s.
- ``glide(AMP, T1, F1, T2, F2, ...)``: a sine of peak AMP whose frequency runs through the
  breakpoints (time, frequency), linear between them, phase continuous, starting at phase
  0 like ``sine``; as long as its last time.
- ``hann()`` / ``hann(DUR)``: a Hann window (0 at both ends, 1 in the middle), stretched to
  what it multiplies: ``sine(250 Hz, 20 V, 12 ms) * hann()`` is a short burst.
- ``env(@NAME)``, ``glide(AMP, @NAME)``, ``bursts(@NAME)``: the same shapes (and a list of
  Hann-windowed sine bursts: time, peak volts, frequency, length) from the breakpoint data
  file ``NAME.json`` beside the library (``console.signals.breakpoint_data``): an imported
  haptic file of any size is a short expression. Only a parse given the library's data
  (``parse(text, data=...)``) resolves ``@NAME``.

Times are strictly increasing (a step is two breakpoints a little apart, which the slew
limit asks for anyway); every mistake is one ``UserError`` naming the part and the fix.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from console.core.errors import UserError
from console.core.plain_numbers import plain_s
from console.signals.design import Node, _below_nyquist
from console.signals.syntax import Quantity

NAMES = ("env", "glide", "hann", "bursts")
#: at most this many breakpoints in one call
MAX_POINTS = 4000


@dataclass(frozen=True)
class Env(Node):
    """Piecewise-linear ratio envelope through ``(times_s[i], levels[i])``."""

    times_s: tuple[float, ...]
    levels: tuple[float, ...]
    text: str = ""
    volts: bool = False

    def duration_s(self) -> float:
        return self.times_s[-1]

    def render(self, fs: int, n: int) -> np.ndarray:
        # the last sample lands on the last breakpoint (an envelope ending at 0 ends at 0)
        return np.interp(np.linspace(0.0, self.times_s[-1], n), self.times_s, self.levels)


@dataclass(frozen=True)
class Glide(Node):
    """A sine of peak ``amp_v`` whose frequency follows ``(times_s[i], freqs_hz[i])``."""

    amp_v: float
    times_s: tuple[float, ...]
    freqs_hz: tuple[float, ...]
    text: str = ""
    volts: bool = True

    def duration_s(self) -> float:
        return self.times_s[-1]

    def render(self, fs: int, n: int) -> np.ndarray:
        for f in self.freqs_hz:
            _below_nyquist(self.text or "glide", f, fs)
        f = np.interp(np.arange(n) / fs, self.times_s, self.freqs_hz)
        # trapezoidal phase: exact for a frequency linear between samples
        phase = np.concatenate([[0.0], np.cumsum(0.5 * (f[1:] + f[:-1]))]) * (2 * np.pi / fs)
        return self.amp_v * np.sin(phase)


@dataclass(frozen=True)
class Hann(Node):
    """A Hann window over ``dur_s`` or stretched to what it multiplies."""

    dur_s: float | None = None
    text: str = ""
    volts: bool = False

    def duration_s(self) -> float | None:
        return self.dur_s

    def render(self, fs: int, n: int) -> np.ndarray:
        return np.hanning(n) if n > 2 else np.zeros(n)


@dataclass(frozen=True, eq=False)
class Bursts(Node):
    """Hann-windowed sine bursts: at ``t_s[i]``, ``v[i]`` peak, ``hz[i]``, ``dur_s[i]`` long
    (sine phase 0 at each start, like ``seq(silence(..), sine(..) * hann())``)."""

    t_s: np.ndarray
    v: np.ndarray
    hz: np.ndarray
    dur_s: np.ndarray
    text: str = ""
    volts: bool = True

    def duration_s(self) -> float:
        return float(np.max(self.t_s + self.dur_s))

    def render(self, fs: int, n: int) -> np.ndarray:
        out = np.zeros(n)
        for t0, v, f, d in zip(self.t_s, self.v, self.hz, self.dur_s, strict=True):
            _below_nyquist(self.text or "bursts", float(f), fs)
            k, m = round(t0 * fs), round(d * fs)
            m = min(m, n - k)
            if m > 0:
                w = np.hanning(round(d * fs))[:m]
                out[k : k + m] += v * w * np.sin(2 * np.pi * f * np.arange(m) / fs)
        return out


@dataclass(frozen=True)
class DataRef:
    """``@NAME`` resolved: the curves of a breakpoint data file."""

    curves: object
    text: str


def data_ref(name: str, part: str, data) -> DataRef:
    """``@name`` in ``part``, looked up in ``data`` (a ``breakpoint_data.Resolver``)."""
    if data is None:
        raise UserError(
            f"{part} is breakpoint data kept beside the signal library; use it in "
            "a library signal or in an expression played with the library (haptable "
            "signals play|show NAME)"
        )
    return DataRef(data(name), f"@{name}")


def _from_data(name: str, args: list, part: str) -> Node | None:
    """The node ``name(..., @NAME)`` makes, or None when no ``@NAME`` is given."""
    refs = [a for a in args if isinstance(a, DataRef)]
    if not refs:
        return None
    usage = {"env": "env(@NAME)", "glide": "glide(AMP, @NAME)", "bursts": "bursts(@NAME)"}
    if name not in usage:
        raise UserError(f"{part}: {name} takes no breakpoint data; use {', '.join(usage.values())}")
    if len(refs) > 1 or args[-1] is not refs[0]:
        raise UserError(f"{part}: breakpoint data goes last and alone; write {usage[name]}")
    ref = refs[0]
    if name == "env":
        if len(args) != 1:
            raise UserError(f"{part}: write env(@NAME) with nothing else")
        c = ref.curves.curve("env", part)
        return Env(tuple(c["t_s"]), tuple(c["level"]), part)
    if name == "bursts":
        if len(args) != 1:
            raise UserError(f"{part}: write bursts(@NAME) with nothing else")
        c = ref.curves.curve("bursts", part)
        return Bursts(c["t_s"], c["v"], c["hz"], c["dur_s"], part)
    if len(args) != 2:
        raise UserError(f"{part}: write glide(AMP, @NAME), e.g. glide(40 V, @NAME)")
    c = ref.curves.curve("glide", part)
    return _glide(args[0], tuple(c["t_s"]), tuple(c["hz"]), part, "glide(AMP, @NAME)")


def _seconds(v, part: str, what: str) -> float:
    if not (isinstance(v, Quantity) and v.dim == "s"):
        shown = v.text if isinstance(v, Quantity) else repr(v)
        raise UserError(f"{part}: {what} {shown} is not a time; write it with s or ms")
    return v.value


def _ratio(v, part: str, what: str) -> float:
    if isinstance(v, Quantity) and v.dim == "dB":
        return 10.0 ** (v.value / 20.0)
    if isinstance(v, Quantity) and v.dim == "ratio":
        return v.value
    if isinstance(v, (int, float)) and not isinstance(v, bool):
        return float(v)
    shown = v.text if isinstance(v, Quantity) else "a signal"
    raise UserError(f"{part}: {what} {shown} is not a level; give a ratio (e.g. 50 %)")


def _hz(v, part: str, what: str) -> float:
    if not (isinstance(v, Quantity) and v.dim == "Hz"):
        shown = v.text if isinstance(v, Quantity) else repr(v)
        raise UserError(f"{part}: {what} {shown} is not a frequency; write it with Hz")
    if v.value <= 0:
        raise UserError(f"{part}: {what} {v.text} must be above 0 Hz")
    return v.value


def _times(values: list, part: str, usage: str) -> tuple[float, ...]:
    if len(values) < 2:
        raise UserError(f"{part}: give at least two breakpoints; {usage}")
    if len(values) > MAX_POINTS:
        raise UserError(f"{part}: {len(values)} breakpoints, at most {MAX_POINTS}; {usage}")
    times = [_seconds(v, part, f"time {i + 1}") for i, v in enumerate(values)]
    if times[0] < 0:
        raise UserError(f"{part}: time 1 is negative; start at 0 s or later")
    for i in range(1, len(times)):
        if not times[i] > times[i - 1]:
            raise UserError(
                f"{part}: time {i + 1} ({plain_s(times[i])}) is not after time {i} "
                f"({plain_s(times[i - 1])}); give strictly increasing times"
            )
    return tuple(times)


def build(name: str, args: list, has_keywords: bool, part: str) -> Node:
    """The node ``name(*args)`` describes (``args`` evaluated by the parser)."""
    if has_keywords:
        raise UserError(f"{part}: {name} takes its values in order, without names")
    if any(isinstance(a, Node) for a in args):
        raise UserError(f"{part}: {name} takes values with units, not signals")
    node = _from_data(name, args, part)
    if node is not None:
        return node
    if name == "bursts":
        raise UserError(f"{part}: bursts take their data from a file: bursts(@NAME)")
    if name == "hann":
        if len(args) > 1:
            raise UserError(f"{part}: hann() or hann(DUR)")
        dur = _seconds(args[0], part, "duration") if args else None
        if dur is not None and dur <= 0:
            raise UserError(f"{part}: duration must be above 0 s")
        return Hann(dur, part)
    if name == "env":
        usage = "env(T1, L1, T2, L2, ...), e.g. env(0 s, 0 %, 20 ms, 100 %, 0.5 s, 0 %)"
        if len(args) % 2:
            raise UserError(f"{part}: an odd number of values; {usage}")
        times = _times(args[0::2], part, usage)
        levels = tuple(_ratio(v, part, f"level {i + 1}") for i, v in enumerate(args[1::2]))
        return Env(times, levels, part)
    usage = "glide(AMP, T1, F1, T2, F2, ...), e.g. glide(20 V, 0 s, 100 Hz, 1 s, 300 Hz)"
    if len(args) % 2 == 0:
        raise UserError(f"{part}: an amplitude then (time, frequency) pairs; {usage}")
    times = _times(args[1::2], part, usage)
    freqs = tuple(_hz(v, part, f"frequency {i + 1}") for i, v in enumerate(args[2::2]))
    return _glide(args[0], times, freqs, part, usage)


def _glide(amp, times: tuple, freqs: tuple, part: str, usage: str) -> Glide:
    volts = not (isinstance(amp, Quantity) and amp.dim in ("ratio", "dB"))
    if volts and not (isinstance(amp, Quantity) and amp.dim == "V"):
        raise UserError(f"{part}: amplitude needs a unit (V or %); {usage}")
    amp_v = amp.value if volts else _ratio(amp, part, "amplitude")
    node = Glide(amp_v, times, freqs, part)
    return node if volts else _ratio_glide(node)


def _ratio_glide(node: Glide) -> Glide:
    return Glide(node.amp_v, node.times_s, node.freqs_hz, node.text, volts=False)
