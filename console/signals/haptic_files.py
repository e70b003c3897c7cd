"""Haptic files in and out: the model AHAP (``console.signals.ahap``) and Meta Haptics
Studio's ``.haptic`` (``console.signals.meta_haptic``) share, and how it maps onto the
table's piezo patches.

A file becomes a ``Pattern``: an amplitude envelope (0..1) and a sharpness / frequency
curve (0..1) on one time grid, plus transients (time, intensity, sharpness). The mapping:

- amplitude 0..1 -> volts as a fraction of ``Scale.peak_v``: by default the largest peak a
  sine may have on the patches (the gate's piezo range, ``[limits] piezo_min_v`` ..
  ``piezo_max_v`` held by the card's full scale times the gain), or ``--level`` in V or in
  dB re 1 V peak, never above that;
- sharpness / frequency 0..1 -> carrier frequency, logarithmic over the actuator's band
  (``[vibrotactile] play_band_hz``, its bottom raised to ``MIN_BAND_HZ``):
  ``f = lo * (hi / lo) ** s``;
- transients -> Hann-windowed bursts of about ``BURST_CYCLES`` cycles of that carrier
  (within ``BURST_S``) starting at the transient's time, peak = intensity x ``peak_v``
  in their middle; bursts that would overlap the one before are dropped;
- a step in level becomes a linear edge of ``EDGE_S`` (the slew limit allows no step), and
  the envelope is held under the gate's start and end ramps (``[limits] ramp_min_ms``);
- audio events and parameters the table has no use for are dropped and listed.

An import (``to_data``) keeps every breakpoint in a data file beside the library
(``console.signals.breakpoint_data``) under an expression naming it (``glide(PEAK, @NAME)
* env(@NAME) + bursts(@NAME)``, ``console.signals.breakpoints``): only grid points on the
straight line between others are merged, within ``DATA_TOL`` (0.001 % of full scale), so a
file of any size imports whole. ``to_expression`` writes the same signal inline
(``seq(silence(...), sine(...) * hann(), ...)`` for the bursts), its breakpoints thinned
to within ``TOLERANCES`` so it fits one expression: for short files and the benchmark. Export goes the other way: the signal's envelope (Hilbert magnitude) and carrier
(Hilbert phase) sampled at breakpoints. Every bad file is one ``UserError`` naming the
file, the key and the fix.
"""

from __future__ import annotations

import math
import re
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np

from console.core.errors import UserError
from console.core.plain_numbers import plain_s
from console.files.file_read import read_bytes_capped
from console.files.json_lines import decode, parse_json
from console.signals.syntax import MAX_EXPR_CHARS

EDGE_S = 1e-3
GRID_S = 0.5e-3
MIN_BAND_HZ = 40.0
BURST_CYCLES = 3.5
BURST_S = (4e-3, 30e-3)
#: envelope tolerances tried in turn (fraction of full scale) until the expression fits
TOLERANCES = (0.001, 0.0025, 0.005, 0.01, 0.02)
MAX_FILE_BYTES = 4 * 2**20
MAX_TIME_S = 3600.0


@dataclass
class Pattern:
    """What a haptic file holds, on one grid: ``amp`` and ``sharp`` in 0..1 at ``t_s``."""

    fmt: str
    path: Path
    t_s: np.ndarray
    amp: np.ndarray
    sharp: np.ndarray
    transients: list[tuple[float, float, float]] = field(default_factory=list)
    mapped: list[str] = field(default_factory=list)
    dropped: list[str] = field(default_factory=list)


@dataclass(frozen=True)
class Scale:
    """Where 0..1 lands: peak volts, the carrier band, the gate's ramp, the sample rate."""

    peak_v: float
    lo_hz: float
    hi_hz: float
    ramp_s: float
    fs: int
    max_s: float = MAX_TIME_S

    def hz(self, s: np.ndarray | float) -> np.ndarray:
        return self.lo_hz * (self.hi_hz / self.lo_hz) ** np.clip(s, 0.0, 1.0)

    def sharpness(self, f_hz: np.ndarray) -> np.ndarray:
        f = np.clip(f_hz, self.lo_hz, self.hi_hz)
        return np.log(f / self.lo_hz) / math.log(self.hi_hz / self.lo_hz)

    def burst_s(self, f_hz: float) -> float:
        """A burst's length: about ``BURST_CYCLES`` cycles within ``BURST_S``, a whole
        number of cycles and a half, so the sine peaks in the Hann window's middle."""
        cycles = f_hz * float(np.clip(BURST_CYCLES / f_hz, *BURST_S))
        return (max(round(cycles - 0.5), 1) + 0.5) / f_hz


# ---------------------------------------------------------------------- reading helpers
def load_json(path: str | Path, what: str) -> Any:
    """The JSON a haptic file holds (bounded read, bad JSON named with its line). A path
    that is not there, or not a file, is told to check the path: its JSON was never read."""
    fix = f"give an {what} file: correct its JSON or save it again from the design tool"
    data = read_bytes_capped(
        path,
        what="haptic file",
        fix=f"give the path of an {what} file",
        max_bytes=MAX_FILE_BYTES,
        missing_ok=True,
    )
    if data is None:
        raise UserError(f"{path}: no such file; check the path (its folder and spelling)")
    return parse_json(decode(data, str(path), fix), str(path), fix)


def bad(path: Path, key: str, problem: str, fix: str) -> UserError:
    return UserError(f"{path}: {key}: {problem}; {fix}")


def num(path: Path, obj: dict, key: str, where: str, lo: float, hi: float, default=None) -> float:
    """``obj[key]`` as a finite number in ``lo..hi`` (``default`` when absent and given)."""
    if key not in obj:
        if default is None:
            raise bad(path, f"{where}.{key}", "missing", f"give a number from {lo:g} to {hi:g}")
        return default
    v = obj[key]
    if isinstance(v, bool) or not isinstance(v, (int, float)) or not math.isfinite(v):
        raise bad(path, f"{where}.{key}", f"{v!r} is not a finite number",
                  f"give a number from {lo:g} to {hi:g}")  # fmt: skip
    if not lo <= v <= hi:
        raise bad(path, f"{where}.{key}", f"{v:g} is outside {lo:g}..{hi:g}",
                  f"give a value from {lo:g} to {hi:g}")  # fmt: skip
    return float(v)


def need(path: Path, value: Any, kind: type, where: str, example: str) -> Any:
    if value is None:
        raise bad(path, where, "missing", f"write {example}")
    if not isinstance(value, kind):
        name = "an object" if kind is dict else "a list"
        raise bad(path, where, f"is {type(value).__name__}, not {name}", f"write {example}")
    return value


def make_grid(end_s: float, key_times: list[float]) -> np.ndarray:
    """A grid every ``GRID_S`` over ``0..end_s`` holding every key time."""
    extra = [t for t in key_times if 0.0 <= t <= end_s]
    return np.unique(np.round(np.concatenate([np.arange(0.0, end_s, GRID_S), extra, [end_s]]), 9))


def strictly(times: list[float], values: list[float]) -> tuple[list[float], list[float]]:
    """Breakpoints with equal times (a step) moved apart by at most ``EDGE_S``."""
    t = list(times)
    for i in range(1, len(t)):
        if t[i] <= t[i - 1]:
            nxt = t[i + 1] if i + 1 < len(t) else t[i - 1] + 2 * EDGE_S
            t[i] = t[i - 1] + max(min(EDGE_S, (nxt - t[i - 1]) / 2), 1e-6)
    return t, list(values)


# ---------------------------------------------------------------------- to a signal
def _simplify(t: np.ndarray, y: np.ndarray, tol: float | np.ndarray) -> np.ndarray:
    """Indices of breakpoints whose linear interpolation is within ``tol`` (a number or
    one per point) of ``y`` everywhere on ``t`` (Ramer-Douglas-Peucker on the vertical
    distance)."""
    tol = np.broadcast_to(np.asarray(tol, float), y.shape)
    keep = np.zeros(t.size, bool)
    keep[[0, -1]] = True
    todo = [(0, t.size - 1)]
    while todo:
        a, b = todo.pop()
        if b - a < 2:
            continue
        line = y[a] + (y[b] - y[a]) * (t[a + 1 : b] - t[a]) / (t[b] - t[a])
        err = np.abs(y[a + 1 : b] - line)
        k = int(np.argmax(err))
        if err[k] > tol[a + 1 + k]:
            m = a + 1 + k
            keep[m] = True
            todo += [(a, m), (m, b)]
    return np.flatnonzero(keep)


def _ramped(t: np.ndarray, amp: np.ndarray, ramp_s: float) -> tuple[np.ndarray, np.ndarray]:
    """``amp`` held under the gate's linear start and end ramps (crossings added)."""
    top, end = float(amp.max()), float(t[-1])
    lines = np.minimum(top * t / ramp_s, top * (end - t) / ramp_s)
    d = amp - lines
    cross = np.flatnonzero(np.sign(d[:-1]) * np.sign(d[1:]) < 0)
    tc = t[cross] + d[cross] / (d[cross] - d[cross + 1]) * (t[cross + 1] - t[cross])
    t2 = np.union1d(t, tc)
    a2 = np.interp(t2, t, amp)
    return t2, np.minimum(a2, np.minimum(top * t2 / ramp_s, top * (end - t2) / ramp_s))


def _ms(t: float) -> str:
    return f"{round(t * 1e3, 2):g} ms"


def _pairs(t: np.ndarray, y: np.ndarray, fmt) -> str:
    out, last = [], None
    for ti, yi in zip(t, y, strict=True):
        shown = _ms(ti)
        if shown != last:
            out.append(f"{shown}, {fmt(yi)}")
            last = shown
    return ", ".join(out)


def _continuous(p: Pattern, scale: Scale, tol: float) -> tuple[str, int]:
    if not np.any(p.amp > 1e-6):
        return "", 0
    t, amp = _ramped(p.t_s, p.amp, scale.ramp_s)
    ka = _simplify(t, amp, tol)
    f_hz = scale.hz(np.interp(t, p.t_s, p.sharp))
    kf = _simplify(t, f_hz, max(tol, 0.002) * f_hz)  # linear in Hz, as glide plays it
    glide = _pairs(t[kf], f_hz[kf], lambda f: f"{round(float(f), 1):g} Hz")
    env = _pairs(t[ka], amp[ka], lambda a: f"{round(float(a) * 100, 3):g} %")
    return f"glide({round(scale.peak_v, 3):g} V, {glide}) * env({env})", ka.size


def _bursts(p: Pattern, scale: Scale) -> tuple[str, int]:
    """The transients' bursts as one ``seq(...)`` expression, and how many were kept."""
    parts, at = [], 0.0
    rows = _burst_rows(p, scale)
    for t0, amp, f, d in rows:
        if t0 > at:
            parts.append(f"silence({_ms(t0 - at)})")
        parts.append(f"sine({round(f, 1):g} Hz, {round(amp, 3):g} V, {_ms(d)}) * hann()")
        at = t0 + round(d * 1e5) / 1e5  # as the expression spells the burst's length
    return (f"seq({', '.join(parts)})" if parts else ""), len(rows)


def _end_factor(t0: float, d: float, end: float, ramp_s: float) -> float:
    """How much a burst at ``t0`` is lowered so it stays under the gate's end ramps."""
    t = t0 + np.linspace(0.0, d, 64)[1:-1]
    win = np.hanning(64)[1:-1]
    line = np.minimum(t / ramp_s, (end - t) / ramp_s)
    return float(min(1.0, np.min(np.maximum(line, 0.0) / win)))


def to_expression(p: Pattern, scale: Scale) -> tuple[str, str]:
    """(the signal expression, a one-line summary of what was mapped and dropped)."""
    # lazy: rendering checks the peak of the sum
    from console.signals.design import render
    from console.signals.expr import parse

    for tol in TOLERANCES:
        cont, n_env = _continuous(p, scale, tol)
        dropped_before = list(p.dropped)
        burst, n_burst = _bursts(p, scale)
        expr = " + ".join(x for x in (cont, burst) if x)
        if len(expr) + 12 <= MAX_EXPR_CHARS:
            break
        p.dropped = dropped_before
    else:
        raise UserError(
            f"{p.path}: the pattern needs more breakpoints than one signal holds "
            f"({len(expr)} characters, at most {MAX_EXPR_CHARS} even at "
            f"{TOLERANCES[-1]:.0%} of full scale); split it into shorter files"
        )
    if not expr:
        raise UserError(f"{p.path}: nothing to play (no haptic event above 0); "
                        "give the file a continuous or transient haptic event")  # fmt: skip
    x = render(parse(expr), scale.fs, max_s=scale.max_s, what=str(p.path))
    peak = float(np.max(np.abs(x)))
    gain = ""
    if peak > scale.peak_v * (1 + 1e-6):
        g = math.floor(scale.peak_v / peak * 1e4) / 100
        expr, gain = f"({expr}) * {g:g} %", f", overlaps lowered to {g:g} %"
    summary = (
        f"{p.path.name} ({p.fmt}): {', '.join(p.mapped)} -> envelope of {n_env} breakpoints "
        f"(within {tol:.1%}), carrier {scale.lo_hz:g}-{scale.hi_hz:g} Hz, {n_burst} bursts, "
        f"peak {min(peak, scale.peak_v):.1f} V{gain}; dropped: "
        + (", ".join(p.dropped) if p.dropped else "nothing")
    )
    return expr, summary


# ---------------------------------------------------------------------- to data
#: what the data keeps: collinear grid points merged, nothing a file holds thinned away
DATA_TOL = 1e-5


def to_data(p: Pattern, scale: Scale, name: str) -> tuple[str, dict, str]:
    """(the expression ``glide(PEAK, @name) * env(@name) + bursts(@name)``, its curves for
    ``console.signals.breakpoint_data``, a one-line summary): every breakpoint of the file
    kept (only points on straight lines between others merged, within ``DATA_TOL``)."""
    from console.signals.design import render  # lazy: rendering checks the peak of the sum
    from console.signals.expr import parse

    curves: dict[str, dict[str, np.ndarray]] = {}
    parts = []
    n_env = 0
    if np.any(p.amp > 1e-6):
        t, amp = _ramped(p.t_s, p.amp, scale.ramp_s)
        ka = _knots(t, amp, DATA_TOL)
        f_hz = scale.hz(np.interp(t, p.t_s, p.sharp))
        kf = _knots(t, f_hz, DATA_TOL * f_hz)
        curves["env"] = {"t_s": t[ka], "level": np.clip(amp[ka], 0.0, 1.0)}
        curves["glide"] = {"t_s": t[kf], "hz": f_hz[kf]}
        parts.append(f"glide({round(scale.peak_v, 3):g} V, @{name}) * env(@{name})")
        n_env = ka.size
    bursts = _burst_rows(p, scale)
    if bursts:
        curves["bursts"] = {k: np.array([b[i] for b in bursts]) for i, k in
                            enumerate(("t_s", "v", "hz", "dur_s"))}  # fmt: skip
        parts.append(f"bursts(@{name})")
    if not parts:
        raise UserError(f"{p.path}: nothing to play (no haptic event above 0); "
                        "give the file a continuous or transient haptic event")  # fmt: skip
    expr = " + ".join(parts)
    data = _Inline(name, curves)
    x = render(parse(expr, data=data), scale.fs, max_s=scale.max_s, what=str(p.path))
    peak = float(np.max(np.abs(x)))
    gain = ""
    if peak > scale.peak_v * (1 + 1e-6):
        g = math.floor(scale.peak_v / peak * 1e4) / 100
        expr, gain = f"({expr}) * {g:g} %", f", overlaps lowered to {g:g} %"
    summary = (
        f"{p.path.name} ({p.fmt}): {', '.join(p.mapped)} -> envelope of {n_env} breakpoints "
        f"(none thinned: within {DATA_TOL:.3%}), carrier {scale.lo_hz:g}-{scale.hi_hz:g} Hz, "
        f"{len(bursts)} bursts, "
        f"peak {min(peak, scale.peak_v):.1f} V{gain}; dropped: "
        + (", ".join(p.dropped) if p.dropped else "nothing")
    )
    return expr, curves, summary


def _knots(t: np.ndarray, y: np.ndarray, tol: float | np.ndarray) -> np.ndarray:
    """``_simplify`` after dropping the grid points that lie on the line through their
    neighbours to rounding (what the grid added between a file's breakpoints): fast on
    grids of many seconds."""
    tol = np.broadcast_to(np.asarray(tol, float), y.shape)
    mid = y[:-2] + (y[2:] - y[:-2]) * (t[1:-1] - t[:-2]) / (t[2:] - t[:-2])
    bent = np.abs(y[1:-1] - mid) > 1e-12 * (1.0 + np.abs(y[1:-1]))
    idx = np.flatnonzero(np.concatenate([[True], bent, [True]]))
    return idx[_simplify(t[idx], y[idx], tol[idx])]


def _burst_rows(p: Pattern, scale: Scale) -> list[tuple[float, float, float, float]]:
    """(time, peak volts, frequency, length) of each transient's burst (as ``_bursts``)."""
    rows, at = [], 0.0
    for t0, level, sharp in sorted(p.transients):
        f = float(scale.hz(sharp))
        d = scale.burst_s(f)
        if t0 < at - 1e-9:
            p.dropped.append(f"transient at {plain_s(t0)} (overlaps the burst before)")
            continue
        k = _end_factor(t0, d, p.t_s[-1], scale.ramp_s)
        if k < 1.0 and not any(x.startswith("bursts lowered") for x in p.mapped):
            p.mapped.append("bursts lowered under the gate's end ramps")
        rows.append((t0, level * scale.peak_v * k, f, d))
        at = t0 + d
    return rows


class _Inline:
    """``@name`` -> the curves not yet written (a render before saving)."""

    def __init__(self, name: str, curves: dict) -> None:
        from console.signals.breakpoint_data import Curves  # lazy: import cycle

        self.curves = Curves(name, Path(f"{name}.json"), **curves)
        self.name = name

    def __call__(self, name: str):
        if name != self.name:
            raise UserError(f"@{name}: only @{self.name} is being imported")
        return self.curves


# ---------------------------------------------------------------------- from a signal
@dataclass(frozen=True)
class Exported:
    """A signal as breakpoints: intensity (0..1) and sharpness (0..1) over time."""

    duration_s: float
    amp_t_s: np.ndarray
    amp: np.ndarray
    sharp_t_s: np.ndarray
    sharp: np.ndarray
    notes: list[str]


def export_signal(x: np.ndarray, scale: Scale, what: str, tol: float = 0.001) -> Exported:
    """``x`` (volts at ``scale.fs``) as an envelope over ``scale.peak_v`` and a carrier
    mapped back onto the band: the Hilbert magnitude and instantaneous frequency."""
    from scipy.signal import hilbert  # lazy: scipy.signal is heavy

    fs = scale.fs
    z = hilbert(x)
    env = np.abs(z) / scale.peak_v
    peak = float(np.max(np.abs(x)))
    if peak > scale.peak_v * (1 + 1e-6):
        raise UserError(
            f"{what} peaks at {peak:.1f} V, above the reference {scale.peak_v:g} V that "
            f"intensity 1 stands for; export with --level {math.ceil(peak)} V"
        )
    step = max(1, round(GRID_S * fs))
    idx = np.arange(0, x.size, step)
    if idx[-1] != x.size - 1:
        idx = np.append(idx, x.size - 1)
    t = idx / fs
    a = np.clip(env[idx], 0.0, 1.0)
    a[[0, -1]] = 0.0 if abs(x[0]) < 1e-9 and abs(x[-1]) < 1e-9 else a[[0, -1]]
    ka = _simplify(t, a, tol)
    inst = np.diff(np.unwrap(np.angle(z))) * fs / (2 * np.pi)
    inst = np.append(inst, inst[-1])
    win = np.lib.stride_tricks.sliding_window_view(np.pad(inst, (0, 4 * step), "edge"), 4 * step)
    f = np.median(win[idx], axis=1)  # the carrier over 4 grid steps, robust to edges
    loud = a > 0.05 * max(a.max(), 1e-12)
    notes = []
    if loud.any():
        f = np.interp(t, t[loud], f[loud])
        if f[loud].max() > scale.hi_hz * 1.01 or f[loud].min() < scale.lo_hz * 0.99:
            notes.append(
                f"carrier {f[loud].min():.0f}-{f[loud].max():.0f} Hz clipped to the band "
                f"{scale.lo_hz:g}-{scale.hi_hz:g} Hz"
            )
    else:
        f = np.full(t.size, scale.lo_hz)
    s = scale.sharpness(f)
    ks = _simplify(t, s, 0.001)  # 0.3 % in frequency over 40-625 Hz
    return Exported(x.size / fs, t[ka], a[ka], t[ks], s[ks], notes)


def safe_name(path: Path) -> str:
    """A library name from a file name (letters, digits, '-' and '_')."""
    name = re.sub(r"[^A-Za-z0-9_-]+", "-", path.stem).strip("-_")[:40]
    return name or "imported"
