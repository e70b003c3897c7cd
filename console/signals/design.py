"""Signals as data: a small tree of waveforms, envelopes and their combinations, rendered
to volts at the actuator by pure numpy/scipy functions.

A node has a length in seconds (``duration_s``) or none (an envelope such as ``ADSR`` or
``Ramp`` stretches to whatever it multiplies). ``render`` checks the whole length against
``[limits] max_plan_s`` (``console.signals.waveforms.check_duration``) before any array is built, so a
repeat of an hour-long tone is refused, not allocated. Expressions an operator types become
these nodes through ``console.signals.expr.parse``.

Amplitudes are peak volts at the actuator; envelopes and gains are plain ratios.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from console.core.errors import UserError
from console.core.plain_numbers import plain_s
from console.core.types import EXCITATIONS, PATCHES, OutputPlan, Segment, patches_of
from console.signals.waveforms import MAX_PLAN_S, plan_samples, ramp_envelope


def _sps():
    """scipy.signal on first use: importing it costs every ``haptable`` command ~1 s."""
    from scipy import signal  # lazy: only a rendered wave, chirp or lowpass needs it

    return signal


class Node:
    """A signal or an envelope. ``text`` is how it reads in an expression (messages)."""

    text: str = ""
    #: True: volts at the actuator; False: a ratio (an envelope, a modulator)
    volts: bool = True

    def duration_s(self) -> float | None:
        """Length in seconds; None for an envelope that stretches to its partner."""
        raise NotImplementedError

    def n_samples(self, fs: int) -> int | None:
        d = self.duration_s()
        return None if d is None else round(d * fs)

    def render(self, fs: int, n: int) -> np.ndarray:
        """``n`` samples at ``fs`` (for a node with a length, ``n == n_samples(fs)``)."""
        raise NotImplementedError


def _below_nyquist(text: str, freq_hz: float, fs: int, *, zero_ok: bool = False) -> None:
    if freq_hz >= fs / 2 or freq_hz < 0 or (freq_hz == 0 and not zero_ok):
        raise UserError(
            f"{text}: {freq_hz:g} Hz cannot play at {fs} Hz sampling; give a frequency "
            f"above 0 and below {fs / 2:g} Hz"
        )


@dataclass(frozen=True)
class Wave(Node):
    """A periodic waveform: ``kind`` is sine, square, saw or triangle; ``amp_v`` peak."""

    kind: str
    freq_hz: float
    amp_v: float
    dur_s: float
    text: str = ""
    volts: bool = True

    def duration_s(self) -> float:
        return self.dur_s

    def render(self, fs: int, n: int) -> np.ndarray:
        _below_nyquist(self.text or self.kind, self.freq_hz, fs)
        phase = 2 * np.pi * self.freq_hz * (np.arange(n) / fs)
        if self.kind == "sine":
            y = np.sin(phase)
        elif self.kind == "square":
            y = _sps().square(phase)
        elif self.kind == "saw":
            y = _sps().sawtooth(phase, width=1.0)
        elif self.kind == "triangle":  # starts at 0 rising, like the sine
            y = _sps().sawtooth(phase + np.pi / 2, width=0.5)
        else:  # pragma: no cover - the parser only builds the four
            raise ValueError(self.kind)
        return self.amp_v * y


@dataclass(frozen=True)
class Chirp(Node):
    """A sweep from ``f0_hz`` to ``f1_hz`` (``log``: logarithmic), sine phase 0 at t = 0."""

    f0_hz: float
    f1_hz: float
    amp_v: float
    dur_s: float
    log: bool = False
    text: str = ""
    volts: bool = True

    def duration_s(self) -> float:
        return self.dur_s

    def render(self, fs: int, n: int) -> np.ndarray:
        for f in (self.f0_hz, self.f1_hz):
            _below_nyquist(self.text or "chirp", f, fs, zero_ok=not self.log)
        t = np.arange(n) / fs
        method = "logarithmic" if self.log else "linear"
        # scipy's chirp is a cosine: phase -90 degrees makes it start at zero like a sine
        return self.amp_v * _sps().chirp(t, self.f0_hz, self.dur_s, self.f1_hz, method, phi=-90)


@dataclass(frozen=True)
class Noise(Node):
    """Uniform white noise within +-``amp_v``, reproducible from ``seed``."""

    amp_v: float
    dur_s: float
    seed: int = 0
    text: str = ""
    volts: bool = True

    def duration_s(self) -> float:
        return self.dur_s

    def render(self, fs: int, n: int) -> np.ndarray:
        return self.amp_v * np.random.default_rng(self.seed).uniform(-1.0, 1.0, n)


@dataclass(frozen=True)
class Silence(Node):
    dur_s: float
    text: str = ""

    def duration_s(self) -> float:
        return self.dur_s

    def render(self, fs: int, n: int) -> np.ndarray:
        return np.zeros(n)


@dataclass(frozen=True)
class ADSR(Node):
    """Attack (0 -> 1), decay (-> ``sustain``), sustain, release (-> 0 at the last sample).
    Without ``dur_s`` the sustain stretches to the length of what it multiplies."""

    attack_s: float
    decay_s: float
    sustain: float
    release_s: float
    dur_s: float | None = None
    text: str = ""
    volts: bool = False

    def duration_s(self) -> float | None:
        return self.dur_s

    def render(self, fs: int, n: int) -> np.ndarray:
        na, nd, nr = (round(t * fs) for t in (self.attack_s, self.decay_s, self.release_s))
        if na + nd + nr > n:
            raise UserError(
                f"{self.text or 'adsr'}: attack + decay + release = "
                f"{plain_s((na + nd + nr) / fs)} is longer than the {plain_s(n / fs)} it shapes; "
                "shorten the envelope or lengthen the signal"
            )
        s = self.sustain
        return np.concatenate(
            [
                np.linspace(0.0, 1.0, na, endpoint=False),
                np.linspace(1.0, s, nd, endpoint=False),
                np.full(n - na - nd - nr, s),
                np.linspace(s, 0.0, nr),
            ]
        )


@dataclass(frozen=True)
class Ramp(Node):
    """Linear rise over ``ramp_s`` at the start and fall at the end (0 at both ends): the
    ramp the safety gate asks for. Stretches to what it multiplies."""

    ramp_s: float
    text: str = ""
    volts: bool = False

    def duration_s(self) -> None:
        return None

    def render(self, fs: int, n: int) -> np.ndarray:
        r = round(self.ramp_s * fs)
        if 2 * r > n:
            raise UserError(
                f"{self.text or 'ramp'}: two {plain_s(self.ramp_s)} ramps do not fit in "
                f"{plain_s(n / fs)}; shorten the ramp"
            )
        return ramp_envelope(n, r)


@dataclass(frozen=True)
class Level(Node):
    """A level going from ``start`` to ``end`` linearly or exponentially (``exp``: both
    above 0), over ``dur_s`` or stretched to what it multiplies."""

    start: float
    end: float
    exp: bool = False
    dur_s: float | None = None
    text: str = ""
    volts: bool = False

    def duration_s(self) -> float | None:
        return self.dur_s

    def render(self, fs: int, n: int) -> np.ndarray:
        if self.exp:
            return np.geomspace(self.start, self.end, n) if n else np.zeros(0)
        return np.linspace(self.start, self.end, n)


@dataclass(frozen=True)
class Gain(Node):
    factor: float
    part: Node
    text: str = ""

    @property
    def volts(self) -> bool:  # type: ignore[override]
        return self.part.volts

    def duration_s(self) -> float | None:
        return self.part.duration_s()

    def n_samples(self, fs: int) -> int | None:
        return self.part.n_samples(fs)

    def render(self, fs: int, n: int) -> np.ndarray:
        return self.factor * self.part.render(fs, n)


@dataclass(frozen=True)
class Lowpass(Node):
    """``part`` through a zero-phase Butterworth low-pass (order 4, run forward and
    backward: ``|H(f)|^2 = 1 / (1 + (f / cutoff)^8)``, no delay): smooths the edges of
    square and saw waves to within the slew limit."""

    part: Node
    cutoff_hz: float
    text: str = ""
    ORDER = 4

    @property
    def volts(self) -> bool:  # type: ignore[override]
        return self.part.volts

    def duration_s(self) -> float | None:
        return self.part.duration_s()

    def n_samples(self, fs: int) -> int | None:
        return self.part.n_samples(fs)

    def render(self, fs: int, n: int) -> np.ndarray:
        _below_nyquist(self.text or "lowpass", self.cutoff_hz, fs)
        y = self.part.render(fs, n)
        if y.size < 2:
            return y
        sos = _sps().butter(self.ORDER, self.cutoff_hz, fs=fs, output="sos")
        pad = min(3 * (2 * len(sos) + 1), y.size - 1)
        return _sps().sosfiltfilt(sos, y, padlen=pad)


def _fit(part: Node, fs: int, n: int) -> np.ndarray:
    """``part`` over ``n`` samples: an envelope stretches, a shorter signal is followed
    by silence."""
    own = part.n_samples(fs)
    if own is None:
        return part.render(fs, n)
    y = part.render(fs, own)
    return np.pad(y, (0, n - own)) if own < n else y


@dataclass(frozen=True)
class Mix(Node):
    """Sum (``op`` "+") or product (``op`` "*") of parts, as long as the longest part with
    a length; envelopes stretch to it and shorter parts end in silence."""

    op: str
    parts: tuple[Node, ...]
    text: str = ""

    @property
    def volts(self) -> bool:  # type: ignore[override]
        return any(p.volts for p in self.parts)

    def duration_s(self) -> float | None:
        ds = [d for p in self.parts if (d := p.duration_s()) is not None]
        return max(ds) if ds else None

    def n_samples(self, fs: int) -> int | None:
        ns = [k for p in self.parts if (k := p.n_samples(fs)) is not None]
        return max(ns) if ns else None

    def render(self, fs: int, n: int) -> np.ndarray:
        out = _fit(self.parts[0], fs, n)
        for p in self.parts[1:]:
            y = _fit(p, fs, n)
            out = out + y if self.op == "+" else out * y
        return out


@dataclass(frozen=True)
class Seq(Node):
    """Parts one after the other (``count`` times over: a repeat)."""

    parts: tuple[Node, ...]
    count: int = 1
    text: str = ""

    @property
    def volts(self) -> bool:  # type: ignore[override]
        return any(p.volts for p in self.parts)

    def duration_s(self) -> float:
        return self.count * sum(p.duration_s() or 0.0 for p in self.parts)

    def n_samples(self, fs: int) -> int:
        return self.count * sum(p.n_samples(fs) or 0 for p in self.parts)

    def render(self, fs: int, n: int) -> np.ndarray:
        once = np.concatenate([p.render(fs, p.n_samples(fs) or 0) for p in self.parts])
        return np.tile(once, self.count)


def render(node: Node, fs: int, *, max_s: float = MAX_PLAN_S, what: str = "signal") -> np.ndarray:
    """``node`` in volts at ``fs``; its length is checked against ``max_s`` before any
    array is built, and the result is refused when not finite."""
    d = node.duration_s()
    if d is None:
        raise UserError(
            f"{what}: {node.text or 'an envelope'} alone has no length; multiply it by a "
            "signal, e.g. sine(250 Hz, 20 V, 1 s) * " + (node.text or "ramp(10 ms)")
        )
    if not node.volts:
        raise UserError(
            f"{what}: {node.text or 'it'} is a ratio (an envelope or a modulator in %), not "
            "volts; multiply it by a signal in volts, e.g. sine(250 Hz, 20 V, 1 s)"
        )
    plan_samples(d, fs, max_s=max_s, what=what)  # refused here, before any allocation
    n = node.n_samples(fs) or 0
    if n < 2:
        raise UserError(f"{what}: {plain_s(d)} is shorter than two samples; give it a length")
    y = node.render(fs, n)
    bad = np.flatnonzero(~np.isfinite(y))
    if bad.size:
        raise UserError(f"{what}: not a number at {plain_s(bad[0] / fs, 4)}; check its values")
    return y


# ---------------------------------------------------------------------- what it holds
def spectrum(x: np.ndarray, fs: int, *, window: bool = True) -> tuple[np.ndarray, np.ndarray]:
    """(frequency in Hz, peak amplitude in V) of ``x`` under a Hann window (``window``
    False: none, the spectrum of the finite signal as it is, so a chirp's start and end
    keep their level): a sine of peak A on a bin reads A."""
    x = np.asarray(x, float)
    w = np.hanning(x.size) if x.size > 1 and window else np.ones(x.size)
    mag = np.abs(np.fft.rfft(x * w)) * 2.0 / max(w.sum(), 1e-12)
    return np.fft.rfftfreq(x.size, 1.0 / fs), mag


def dominant_hz(x: np.ndarray, fs: int) -> float:
    """The strongest frequency above 0 Hz (parabolic interpolation on the log spectrum);
    0 for silence."""
    f, mag = spectrum(x, fs)
    if mag.size < 3 or not np.any(mag[1:]):
        return 0.0
    k = 1 + int(np.argmax(mag[1:]))
    if 1 <= k < mag.size - 1:
        a, b, c = np.log(np.maximum(mag[k - 1 : k + 2], 1e-300))
        den = a - 2 * b + c
        delta = 0.5 * (a - c) / den if den < 0 else 0.0
        return float(f[k] + delta * (f[1] - f[0]))
    return float(f[k])


@dataclass(frozen=True)
class Summary:
    duration_s: float
    peak_v: float
    rms_v: float
    dominant_hz: float

    def line(self) -> str:
        return (
            f"{self.duration_s:.3f} s, peak {self.peak_v:.2f} V, RMS {self.rms_v:.2f} V, "
            f"dominant {self.dominant_hz:.1f} Hz"
        )


def summarize(x: np.ndarray, fs: int) -> Summary:
    x = np.asarray(x, float)
    return Summary(
        duration_s=x.size / fs,
        peak_v=float(np.max(np.abs(x))) if x.size else 0.0,
        rms_v=float(np.sqrt(np.mean(x**2))) if x.size else 0.0,
        dominant_hz=dominant_hz(x, fs),
    )


# ---------------------------------------------------------------------- where it plays
@dataclass(frozen=True)
class Target:
    """Where a signal plays: piezo ``patches`` (their relays closed) or the ``screen``."""

    patches: frozenset[str] = frozenset()
    screen: bool = False

    @property
    def label(self) -> str:
        return "screen" if self.screen else ",".join(sorted(self.patches))


SCREEN = Target(screen=True)


def parse_target(text: str) -> Target:
    """``PA``, ``PA,PC`` / ``PA+PC``, ``PALL`` or ``screen`` -> a ``Target``."""
    parts = [p.strip() for p in str(text).replace("+", ",").split(",") if p.strip()]
    if not parts:
        raise UserError("no target: give patches (PA, PA,PC, PALL) or screen")
    if any(p.lower() == "screen" for p in parts):
        if len(parts) > 1:
            raise UserError(
                f"target {text!r}: the screen plays alone; give patches or screen, not both"
            )
        return SCREEN
    patches: set[str] = set()
    for p in parts:
        name = p.upper()
        if name not in EXCITATIONS:
            raise UserError(
                f"target {text!r}: unknown patch {p!r}; use {', '.join(PATCHES)}, PALL "
                "or screen (combine patches as PA,PC)"
            )
        patches |= patches_of(name)
    return Target(frozenset(patches))


def signal_plan(volts: np.ndarray, target: Target, fs: int, name: str) -> OutputPlan:
    """One segment playing ``volts`` on ``target`` (the other channel silent)."""
    v = np.asarray(volts, float)
    z = np.zeros_like(v)
    seg = (
        Segment(z, v, frozenset(), True, f"{name} on the screen")
        if target.screen
        else Segment(v, z, target.patches, False, f"{name} on {target.label}")
    )
    return OutputPlan(fs, (seg,), name=name)
