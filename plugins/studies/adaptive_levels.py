"""Levels of an adaptive procedure: dB to volts at the actuator, the gate's largest level,
and a trial's intervals as one ``OutputPlan`` (pure numpy).

A level is in dB re 1 V peak at the actuator (the piezo patches of an excitation, or the
screen's electrovibration electrode), or in dB re 1 um peak of the map's predicted
displacement at a grid point: ``L = 20 log10(V |H(f)|)`` with ``|H(f)|`` the vibration
map's displacement per volt at the point for the excitation (``frf_um_per_v``, linear in
frequency between its unmasked bins), as the vibrotactile effects predict it.

``max_volts(limits, segment)``: the largest scale of a unit-peak stimulus the safety gate
accepts, from the profile's ``[limits]`` as the gate reads them (``Limits``): the channel's
range (and what the amplifier can give), the relay rating in Vpp, and the slew limit
(largest change per sample for the patches it drives). The gate checks are linear in the
amplitude, so this is exact; the procedure's grid is cut at ``max_level_db`` and volts are
clamped to it, so no level the gate would refuse is ever proposed.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from console.plugin_api import Limits, OutputPlan, Segment, UserError, patches_of, smooth_square

#: a square's edges take this long (or a quarter period, whichever is shorter)
SQUARE_EDGE_S = 2e-4


@dataclass(frozen=True)
class Channel:
    """Where a level is played: ``modality`` (``vibrotactile``: the piezo patches of
    ``actuator``; ``electrovibration``: the screen), and ``um_per_v`` (|H| at each
    frequency, vibrotactile with ``reference = "dB re 1 um"``; else empty)."""

    modality: str
    actuator: str = ""
    point: int | None = None
    um_per_v: tuple[tuple[float, float], ...] = ()  # (freq_hz, |H|) pairs


def um_per_v(vmap, point: int, actuator: str, freq_hz: float, where: str = "protocol") -> float:
    """The map's displacement per volt (um/V peak) at grid ``point`` for ``actuator`` at
    ``freq_hz``: |FRF| linear in frequency between unmasked bins."""
    try:
        e = vmap.excitation_index(actuator)
        p = vmap.point_index(int(point))
    except (UserError, ValueError, IndexError, KeyError) as exc:
        raise UserError(f"{where}: stimulus point {point} / actuator {actuator}: {exc}") from None
    keep = ~np.asarray(vmap.masked, bool)
    f = np.asarray(vmap.freq_hz, float)[keep]
    h = np.abs(np.asarray(vmap.frf_um_per_v)[e, p, keep])
    if f.size == 0 or not f[0] <= freq_hz <= f[-1]:
        raise UserError(
            f"{where}: {freq_hz:g} Hz is outside the vibration map's usable bins "
            f"({f[0] if f.size else 0:g}..{f[-1] if f.size else 0:g} Hz); use frequencies inside it"
        )
    g = float(np.interp(freq_hz, f, h))
    if not g > 0:
        raise UserError(
            f"{where}: the map predicts no displacement at point {point} for {actuator} at "
            f"{freq_hz:g} Hz; pick another point, actuator or frequency"
        )
    return g


def unit_wave(freq_hz: float, waveform: str, dur_s: float, ramp_s: float, fs: int) -> np.ndarray:
    """A unit-peak sine or square (edges ``SQUARE_EDGE_S``) under linear ramps: exactly
    0 V at both ends."""
    n = int(round(dur_s * fs))
    r = max(1, min(int(round(ramp_s * fs)), n // 2))
    env = np.ones(n)
    env[:r] = np.arange(r) / r
    env[n - r :] = np.minimum(env[n - r :], (np.arange(r) / r)[::-1])
    env[-1] = 0.0
    phase = 2 * np.pi * freq_hz * np.arange(n) / fs
    if waveform == "square":
        w = smooth_square(phase, min(SQUARE_EDGE_S * freq_hz, 0.25))
    else:
        w = np.sin(phase)
    return w * env


def segment(ch: Channel, v: np.ndarray, label: str = "") -> Segment:
    """``v`` (volts) on the channel: the patches of the actuator, or the screen."""
    z = np.zeros_like(v)
    if ch.modality == "electrovibration":
        return Segment(piezo_v=z, screen_v=v, patches=frozenset(), screen=True, label=label)
    return Segment(piezo_v=v, screen_v=z, patches=patches_of(ch.actuator), label=label)


def max_volts(limits: Limits, seg: Segment) -> float:
    """The largest factor the unit-peak ``seg`` may be scaled by and pass the gate's
    range, relay-rating and slew checks (``console.safety.limits.check_plan``)."""
    cols = limits.layout.columns(seg)
    ranges = limits.column_ranges()
    steps = limits.column_steps_v(frozenset(seg.patches))
    best = math.inf
    for k, x in enumerate(cols):
        x = np.asarray(x, float)
        if not np.any(x):
            continue
        lo, hi = ranges[k]
        if x.max() > 0:
            best = min(best, hi / x.max())
        if x.min() < 0:
            best = min(best, lo / x.min())
        best = min(best, limits.rating_vpp / (x.max() - x.min()))
        d = np.abs(np.diff(x, prepend=0.0, append=0.0)).max()
        best = min(best, float(steps[k]) / d)
    return float(best)


def db_offset(ch: Channel, freq_hz: float) -> float:
    """``L - 20 log10(V)``: 0 for dB re 1 V, ``20 log10 |H(f)|`` for dB re 1 um."""
    for f, h in ch.um_per_v:
        if f == freq_hz:
            return 20.0 * math.log10(h)
    return 0.0


def volts(level_db: float, ch: Channel, freq_hz: float, cap_v: float) -> float:
    """The peak volts of a level, never above ``cap_v`` (the gate's largest)."""
    return min(10.0 ** ((level_db - db_offset(ch, freq_hz)) / 20.0), cap_v)


def level_of(peak_v: float, ch: Channel, freq_hz: float) -> float:
    """The level (dB) of a peak voltage."""
    return 20.0 * math.log10(peak_v) + db_offset(ch, freq_hz) if peak_v > 0 else -math.inf


def trial_plan(
    ch: Channel,
    unit: np.ndarray,
    peaks_v: list[float],
    fs: int,
    gap_s: float,
    name: str,
) -> OutputPlan:
    """The intervals of a trial in order, ``peaks_v[i]`` volts in interval ``i`` (0: a
    silent interval on the same channel, so the relays do not tell it apart)."""
    segs = tuple(
        segment(ch, unit * float(v), label=f"interval {i + 1}") for i, v in enumerate(peaks_v)
    )
    return OutputPlan(sample_rate_hz=fs, segments=segs, name=name, gap_s=gap_s)


def interval_peaks_v(plan: OutputPlan, modality: str) -> list[float]:
    """The peak volts of each interval of a played plan (what the observer feels)."""
    out = []
    for seg in plan.segments:
        x = seg.screen_v if modality == "electrovibration" else seg.piezo_v
        out.append(float(np.max(np.abs(x))) if np.size(x) else 0.0)
    return out
