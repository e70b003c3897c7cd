"""Live streams synthesised from parameters: what the safety kernel plays for a plugin.

No plugin code runs where the outputs are. A plugin describes its live stream once, as a
``StreamSpec`` (plain data; ``to_json`` / ``from_json`` cross a socket, validated
strictly), and from then on only posts *targets* to a ``StreamSynth``: crossing ids that
trigger the stream's pulse, and the carrier's frequency and amplitude. The synth renders
``next_block(n) -> (piezo_v, screen_v)`` in volts at the actuator.

What it plays (the knob's feedback, paper 5.4, is the first user):

* the **carrier**, a sine on the screen channel. Each block glides its frequency and
  amplitude linearly from where the last block ended toward the latest targets, reaching
  them ``glide_ms`` after the block's start (blocks shorter than that approach them
  piecewise, by the same fraction per block). The phase is accumulated, never reset.
  While the amplitude target is 0 the frequency holds where it is (a fading carrier keeps
  its pitch, and glides on from there when it comes back). Targets are clamped into
  ``0..carrier_max_v`` and ``carrier_min_hz..carrier_max_hz``; NaN and inf are ignored.
* an optional **pulse** per crossing (``PulseSpec``), at the first sample of the block
  after the post; a crossing during a pulse extends it without a jump:

  - ``"square"``: raised-cosine edges of ``edge_ms``, held so the whole pulse lasts
    ``length_ms``. With ``freq_hz`` 0 it is one flat pulse whose polarity alternates
    from pulse to pulse (no net charge); else a smooth square wave at ``freq_hz``;
  - ``"burst"``: a sine at ``freq_hz`` under a Hann window of ``length_ms``.

  On the screen a pulse ducks the carrier as a convex mix (``carrier * (1 - env) + pulse
  * env``), so the peak never exceeds the larger of the two.
* the **master ramp**: raised cosine in over ``ramp_ms`` from an exact 0 (the gate's start
  rule), and out over ``ramp_ms`` after ``request_stop()``; then ``next_block`` returns
  ``None``.

The output never exceeds ``declared_peak_v(spec)`` on either channel (by construction; a
final clip removes rounding). ``spec_problem`` says why the kernel must refuse a spec.
"""

from __future__ import annotations

import math
import numbers
import operator
import reprlib
import threading
import time
from collections import deque
from collections.abc import Iterable, Mapping, Sequence
from dataclasses import dataclass
from typing import Any, ClassVar, Protocol, runtime_checkable

import numpy as np

from console.core.types import PATCHES

#: bus channels a stream declares a peak for
CHANNELS: tuple[str, ...] = ("piezo", "screen")
#: pulse shapes
SHAPES: tuple[str, ...] = ("square", "burst")
MIN_RATE_HZ, MAX_RATE_HZ = 1000, 384000
MAX_MS = 60000.0  # the longest ramp, glide or pulse a spec may ask for
LOG_LEN = 100000  # default length of ``detent_log`` and ``trace``
PENDING_MAX = 10000  # crossings kept between two blocks (more: the oldest are not logged)


# --------------------------------------------------------------------------- shaping
class Envelope:
    """A 0..1 gate with raised-cosine edges: ``trigger()`` (re)starts a hold of
    ``hold_n`` samples (``None`` = until ``release()``); the level is always continuous."""

    def __init__(self, edge_n: int, hold_n: int | None) -> None:
        self.edge_n = max(int(edge_n), 1)
        self.hold_n = hold_n
        self.k = 0.0  # position on the edge, 0..edge_n (level = 0.5 - 0.5 cos(pi k / edge_n))
        self.state = "idle"  # idle | rise | hold | fall
        self.hold_left = 0

    @property
    def level(self) -> float:
        return 0.5 - 0.5 * math.cos(math.pi * max(self.k, 0.0) / self.edge_n)

    @property
    def active(self) -> bool:
        return self.state != "idle"

    def trigger(self) -> None:
        self.hold_left = self.hold_n if self.hold_n is not None else -1
        if self.state in ("idle", "fall"):
            self.state = "rise"

    def release(self) -> None:
        if self.state != "idle":
            self.state = "fall"

    def block(self, n: int) -> np.ndarray:
        out = np.empty(n)
        i = 0
        e = self.edge_n
        while i < n:
            if self.state == "idle":
                out[i:] = 0.0
                break
            if self.state == "hold":
                if self.hold_left < 0:
                    out[i:] = 1.0
                    break
                m = min(self.hold_left, n - i)
                out[i : i + m] = 1.0
                i += m
                self.hold_left -= m
                if self.hold_left == 0:
                    self.state = "fall"
                continue
            step = 1.0 if self.state == "rise" else -1.0
            left = (e - self.k) if step > 0 else self.k
            m = max(min(int(math.ceil(left - 1e-9)), n - i), 0)
            ks = self.k + step * np.arange(1, m + 1)
            ks = np.clip(ks, 0.0, e)
            out[i : i + m] = 0.5 - 0.5 * np.cos(np.pi * ks / e)
            self.k = float(ks[-1]) if m else self.k
            i += m
            if step > 0 and self.k >= e:
                self.state = "hold"
                if self.hold_left == 0:
                    self.state = "fall"
            elif step < 0 and self.k <= 0:
                self.state = "idle"
        return out


def smooth_square(phase: np.ndarray, edge_frac: float) -> np.ndarray:
    """A square wave of ``phase`` (rad) whose transitions take ``edge_frac`` of a period."""
    g = 1.0 / math.sin(math.pi * min(max(edge_frac, 1e-4), 0.5))
    return np.clip(g * np.sin(phase), -1.0, 1.0)


# --------------------------------------------------------------------------- validation
def _fail(path: str, value: Any, allowed: str) -> ValueError:
    shown = reprlib.repr(value)  # short: the value may come from a buggy client
    if not isinstance(value, float):
        shown += f" ({type(value).__name__})"
    return ValueError(f"stream spec {path} = {shown}: {allowed}")


def _real(path: str, x: Any, lo: float, hi: float, unit: str, *, lo_open: bool = False) -> float:
    """``x`` as a float in ``lo..hi`` (``lo`` excluded with ``lo_open``), else ValueError."""
    if math.isinf(hi):
        span = f"> {lo:g}" if lo_open else f">= {lo:g}"
    else:
        span = f"> {lo:g} and <= {hi:g}" if lo_open else f"in {lo:g}..{hi:g}"
    allowed = f"use a finite number {span} {unit}".rstrip()
    if isinstance(x, bool) or not isinstance(x, numbers.Real):
        raise _fail(path, x, allowed)
    v = float(x)
    if not (math.isfinite(v) and lo <= v <= hi) or (lo_open and v == lo):
        raise _fail(path, v, allowed)
    return v


def _choice(path: str, x: Any, allowed: tuple[str, ...]) -> str:
    if not isinstance(x, str) or x not in allowed:
        raise _fail(path, x, "use one of " + ", ".join(repr(a) for a in allowed))
    return x


def _keys(path: str, d: Any, keys: tuple[str, ...]) -> None:
    where = f"stream spec {path}" if path else "stream spec"
    if not isinstance(d, Mapping):
        raise ValueError(f"{where}: expected a JSON object, got {type(d).__name__}")
    listed = ", ".join(keys)
    for k in d:
        if k not in keys:
            raise ValueError(f"{where}: unknown key {reprlib.repr(k)}: the keys are {listed}")
    for k in keys:
        if k not in d:
            raise ValueError(f"{where}: missing key {k!r}: the keys are {listed}")


def _patches(x: Any) -> frozenset[str]:
    allowed = "use a list of distinct patch names out of " + ", ".join(PATCHES)
    if isinstance(x, str | bytes | Mapping) or not isinstance(x, Iterable):
        raise _fail("patches", x, allowed)
    names = list(x)
    for p in names:
        if not isinstance(p, str) or p not in PATCHES:
            raise _fail("patches", p, allowed)
    if len(set(names)) != len(names):
        raise _fail("patches", sorted(names), allowed)
    return frozenset(names)


# --------------------------------------------------------------------------- specs
@dataclass(frozen=True)
class PulseSpec:
    """The pulse each crossing triggers (see the module docstring).

    ``shape`` ``"square"`` | ``"burst"``; ``channel`` ``"screen"`` (ducks the carrier) |
    ``"piezo"``; ``peak_v`` its peak; ``freq_hz`` the square's (0: one flat pulse of
    alternating polarity) or the burst's sine; ``length_ms`` the whole pulse, edges
    included; ``edge_ms`` the square's raised-cosine edge (a burst has none of its own:
    its Hann edges are half of ``length_ms`` each, so it must be 0).
    """

    shape: str
    channel: str
    peak_v: float
    freq_hz: float
    length_ms: float
    edge_ms: float

    KEYS: ClassVar[tuple[str, ...]] = (
        "shape",
        "channel",
        "peak_v",
        "freq_hz",
        "length_ms",
        "edge_ms",
    )

    def __post_init__(self) -> None:
        shape = _choice("pulse.shape", self.shape, SHAPES)
        _choice("pulse.channel", self.channel, CHANNELS)
        fix = object.__setattr__
        fix(self, "peak_v", _real("pulse.peak_v", self.peak_v, 0.0, math.inf, "V"))
        burst = shape == "burst"
        fix(
            self,
            "freq_hz",
            _real("pulse.freq_hz", self.freq_hz, 0.0, MAX_RATE_HZ / 2, "Hz", lo_open=burst),
        )
        fix(
            self,
            "length_ms",
            _real("pulse.length_ms", self.length_ms, 0, MAX_MS, "ms", lo_open=True),
        )
        if burst:
            if isinstance(self.edge_ms, bool) or self.edge_ms != 0:
                raise _fail(
                    "pulse.edge_ms",
                    self.edge_ms,
                    "a burst's Hann edges are half of length_ms each; use 0",
                )
            fix(self, "edge_ms", 0.0)
        else:
            fix(
                self, "edge_ms", _real("pulse.edge_ms", self.edge_ms, 0, MAX_MS, "ms", lo_open=True)
            )

    def to_json(self) -> dict[str, Any]:
        return {k: vars(self)[k] for k in self.KEYS}

    @classmethod
    def from_json(cls, d: Any) -> PulseSpec:
        _keys("pulse", d, cls.KEYS)
        return cls(**{k: d[k] for k in cls.KEYS})


@dataclass(frozen=True)
class StreamSpec:
    """A live stream, described once (see the module docstring).

    ``patches`` the piezo patches it reaches (their relays close), ``screen`` whether it
    plays on the screen; the carrier: at most ``carrier_max_v`` (peak; 0: no carrier),
    ``carrier_min_hz..carrier_max_hz``, starting at ``start_hz``, gliding over
    ``glide_ms``; the master raised-cosine ramp ``ramp_ms``; ``pulse`` or ``None``.
    """

    sample_rate_hz: int
    patches: frozenset[str]
    screen: bool
    carrier_max_v: float
    carrier_min_hz: float
    carrier_max_hz: float
    start_hz: float
    glide_ms: float
    ramp_ms: float
    pulse: PulseSpec | None = None

    KEYS: ClassVar[tuple[str, ...]] = (
        "sample_rate_hz",
        "patches",
        "screen",
        "carrier_max_v",
        "carrier_min_hz",
        "carrier_max_hz",
        "start_hz",
        "glide_ms",
        "ramp_ms",
        "pulse",
    )

    def __post_init__(self) -> None:
        fix = object.__setattr__
        fs = self.sample_rate_hz
        if isinstance(fs, bool) or not isinstance(fs, numbers.Integral):
            raise _fail("sample_rate_hz", fs, f"use an integer in {MIN_RATE_HZ}..{MAX_RATE_HZ} Hz")
        fs = int(fs)
        if not MIN_RATE_HZ <= fs <= MAX_RATE_HZ:
            raise _fail("sample_rate_hz", fs, f"use an integer in {MIN_RATE_HZ}..{MAX_RATE_HZ} Hz")
        fix(self, "sample_rate_hz", fs)
        fix(self, "patches", _patches(self.patches))
        if not isinstance(self.screen, bool):
            raise _fail("screen", self.screen, "use true or false")
        nyq = fs / 2
        fix(self, "carrier_max_v", _real("carrier_max_v", self.carrier_max_v, 0, math.inf, "V"))
        lo = _real("carrier_min_hz", self.carrier_min_hz, 0, nyq, "Hz", lo_open=True)
        fix(self, "carrier_min_hz", lo)
        hi = _real("carrier_max_hz", self.carrier_max_hz, lo, nyq, "Hz (from carrier_min_hz)")
        fix(self, "carrier_max_hz", hi)
        fix(self, "start_hz", _real("start_hz", self.start_hz, lo, hi, "Hz (the carrier's range)"))
        fix(self, "glide_ms", _real("glide_ms", self.glide_ms, 0, MAX_MS, "ms"))
        fix(self, "ramp_ms", _real("ramp_ms", self.ramp_ms, 0, MAX_MS, "ms", lo_open=True))
        p = self.pulse
        if p is not None and not isinstance(p, PulseSpec):
            raise _fail("pulse", p, "use a PulseSpec or None")
        if self.carrier_max_v > 0 and not self.screen:
            raise _fail("screen", False, "the carrier plays on the screen; set it true")
        if p is not None:
            if p.freq_hz > nyq:
                raise _fail("pulse.freq_hz", p.freq_hz, f"use at most sample_rate_hz / 2 = {nyq:g}")
            if p.channel == "screen" and not self.screen:
                raise _fail("screen", False, "the pulse plays on the screen; set it true")
            if p.channel == "piezo" and not self.patches:
                raise _fail(
                    "patches", [], "a piezo pulse needs one or more of " + ", ".join(PATCHES)
                )

    def to_json(self) -> dict[str, Any]:
        """A plain JSON-able dict (``from_json`` reads it back)."""
        d = {k: vars(self)[k] for k in self.KEYS}
        d["patches"] = sorted(self.patches)
        d["pulse"] = self.pulse.to_json() if self.pulse is not None else None
        return d

    @classmethod
    def from_json(cls, d: Any) -> StreamSpec:
        """A spec from a JSON object; ``ValueError`` naming the field and what is allowed
        (wrong type, NaN or inf, out of range, unknown name, missing or extra key)."""
        _keys("", d, cls.KEYS)
        kw = {k: d[k] for k in cls.KEYS}
        if not isinstance(kw["patches"], list):
            raise _fail("patches", kw["patches"], "use a list of patch names (PA..PD)")
        if kw["pulse"] is not None:
            kw["pulse"] = PulseSpec.from_json(kw["pulse"])
        return cls(**kw)


def declared_peak_v(spec: StreamSpec) -> dict[str, float]:
    """The largest |volts| the stream can produce per bus channel (``piezo``, ``screen``)."""
    p = spec.pulse
    pulse_v = {ch: (p.peak_v if p is not None and p.channel == ch else 0.0) for ch in CHANNELS}
    return {"piezo": pulse_v["piezo"], "screen": max(spec.carrier_max_v, pulse_v["screen"])}


def spec_problem(
    spec: StreamSpec,
    *,
    piezo_lo_v: float,
    piezo_hi_v: float,
    screen_peak_v: float,
    ramp_min_ms: float,
    sample_rate_hz: int,
) -> str | None:
    """Why the kernel must refuse to open this stream (one line naming the field and the
    fix), or ``None`` when it may play."""
    if not all(math.isfinite(x) for x in (piezo_lo_v, piezo_hi_v, screen_peak_v, ramp_min_ms)):
        return "the outputs' limits are not all finite numbers; check the profile's [limits]"
    if spec.sample_rate_hz != int(sample_rate_hz):
        return (
            f"sample_rate_hz = {spec.sample_rate_hz}: the outputs run at {int(sample_rate_hz)} Hz; "
            "build the stream for that rate"
        )
    peak = declared_peak_v(spec)
    if peak["piezo"] > 0 and (peak["piezo"] > piezo_hi_v or -peak["piezo"] < piezo_lo_v):
        return (
            f"pulse.peak_v = {peak['piezo']:g} V on the piezo: outside the limits "
            f"{piezo_lo_v:g}..{piezo_hi_v:g} V; lower it"
        )
    if peak["screen"] > 0 and peak["screen"] > screen_peak_v:
        field = "carrier_max_v" if spec.carrier_max_v >= peak["screen"] else "pulse.peak_v"
        return (
            f"{field} = {peak['screen']:g} V peak on the screen: above the limit "
            f"{screen_peak_v:g} V peak; lower it"
        )
    # a raised cosine of length L stays under the gate's linear ramp of length R (at full
    # scale) only when L >= pi/2 R: its steepest slope is pi / (2 L)
    need_ms = math.pi / 2 * float(ramp_min_ms)
    if spec.ramp_ms < need_ms * (1 - 1e-12):
        return (
            f"ramp_ms = {spec.ramp_ms:g}: a raised-cosine ramp must last at least pi/2 x the "
            f"gate's ramp_min_ms ({float(ramp_min_ms):g}) = {need_ms:.4g} ms; lengthen it"
        )
    return None


# --------------------------------------------------------------------------- synthesis
@runtime_checkable
class StreamSink(Protocol):
    """Where a plugin posts a live stream's targets: a local ``StreamSynth`` or the
    outputs process's handle of one."""

    def post(
        self,
        ids: Sequence[int] = (),
        carrier_hz: float | None = None,
        carrier_v: float | None = None,
    ) -> None: ...

    def request_stop(self) -> None: ...


def _target(x: Any, lo: float, hi: float) -> float | None:
    """``x`` clamped into ``lo..hi``; ``None`` for anything that is not a finite number."""
    if isinstance(x, bool) or not isinstance(x, numbers.Real):
        return None
    v = float(x)
    return min(max(v, lo), hi) if math.isfinite(v) else None


class StreamSynth:
    """Renders a ``StreamSpec`` block by block (see the module docstring).

    ``post`` and ``request_stop`` may be called from any thread; ``next_block`` from one
    (the audio path). ``detent_log`` holds (crossing id, sample index where its pulse
    started or was extended), ``trace`` per block (first sample, target Hz, target V);
    both are bounded deques (``log_len``; assign a shorter deque to shorten them).
    """

    def __init__(self, spec: StreamSpec, *, log_len: int = LOG_LEN) -> None:
        if not isinstance(spec, StreamSpec):
            raise TypeError(f"StreamSynth needs a StreamSpec, not {type(spec).__name__}")
        self.spec = spec
        self.fs = spec.sample_rate_hz
        ms = self.fs / 1000.0
        self._peak_v = declared_peak_v(spec)
        self._master = Envelope(round(spec.ramp_ms * ms), None)
        self._master.trigger()
        self._master.k = -1.0  # the first sample is exactly zero (the gate's start rule)
        p = spec.pulse
        self._pulse_env: Envelope | None = None
        if p is not None and p.shape == "square":
            edge_n = max(round(p.edge_ms * ms), 1)
            self._pulse_env = Envelope(edge_n, max(round(p.length_ms * ms) - 2 * edge_n, 0))
        elif p is not None:
            self._pulse_env = Envelope(max(round(p.length_ms * ms), 4) // 2, 0)  # Hann
        self._glide_n = max(round(spec.glide_ms * ms), 1)

        self._lock = threading.Lock()
        self._pending: deque[int] = deque(maxlen=PENDING_MAX)
        #: crossing id -> when its post arrived (monotonic s), until its pulse is logged
        self._arrived_s: dict[int, float] = {}
        self._target_hz = spec.start_hz
        self._target_v = 0.0
        self._stop = False
        self._done = False

        self._phase = 0.0
        self._pulse_phase = 0.0
        self._freq_hz = spec.start_hz
        self._amp_v = 0.0  # the master ramp and the glide start from silence
        self._polarity = 1.0
        self.samples_out = 0
        #: (crossing id, sample index where its pulse started or was extended)
        self.detent_log: deque[tuple[int, int]] = deque(maxlen=log_len)
        #: per block: (first sample, target frequency Hz, target amplitude V)
        self.trace: deque[tuple[int, float, float]] = deque(maxlen=log_len)

    # ------------------------------------------------------------------ inputs
    def post(
        self,
        ids: Sequence[int] = (),
        carrier_hz: float | None = None,
        carrier_v: float | None = None,
    ) -> None:
        """Crossings (each id starts or extends a pulse at the first sample of the next
        block) and carrier targets (``None``, NaN, inf: unchanged; else clamped into the
        spec's range). Any thread; ``TypeError`` for an id that is not an integer."""
        got = [operator.index(i) for i in ids]  # all checked before anything changes
        s = self.spec
        f = _target(carrier_hz, s.carrier_min_hz, s.carrier_max_hz)
        v = _target(carrier_v, 0.0, s.carrier_max_v)
        now = time.monotonic()
        with self._lock:
            self._pending.extend(got)
            for i in got:
                self._arrived_s.setdefault(i, now)
            while len(self._arrived_s) > PENDING_MAX:
                del self._arrived_s[next(iter(self._arrived_s))]
            if f is not None:
                self._target_hz = f
            if v is not None:
                self._target_v = v

    def arrival_s(self, crossing: int) -> float:
        """When crossing ``crossing``'s post arrived (monotonic s; NaN if unknown), once:
        the audio path reads it when it logs the pulse."""
        with self._lock:
            return self._arrived_s.pop(crossing, math.nan)

    def request_stop(self) -> None:
        """Ramp down over ``ramp_ms``; then ``next_block`` returns ``None``."""
        with self._lock:
            self._stop = True

    @property
    def done(self) -> bool:
        """True once the stream has ramped down after ``request_stop()``."""
        return self._done

    # ------------------------------------------------------------------ output
    def next_block(self, n: int) -> tuple[np.ndarray, np.ndarray] | None:
        """The next ``n`` samples (``n`` >= 1) as (piezo_v, screen_v), or ``None`` once
        the stream has ramped down after ``request_stop()``."""
        if self._done:
            return None
        n = operator.index(n)
        if n < 1:
            raise ValueError(f"next_block: n = {n}; ask for one sample or more")
        with self._lock:
            ids = list(self._pending)
            self._pending.clear()
            stop = self._stop
            f_target, a1 = self._target_hz, self._target_v
        f1 = f_target if a1 > 0.0 else self._freq_hz  # a silent carrier holds its frequency
        start = self.samples_out
        if stop:
            self._master.release()
        s, p, env = self.spec, self.spec.pulse, self._pulse_env
        if ids:
            if p is not None and env is not None:
                if p.shape == "square" and not env.active:
                    self._polarity = -self._polarity
                env.trigger()
            for cid in ids:
                self.detent_log.append((cid, start))
        self.trace.append((start, f1, a1))

        idx = np.arange(1, n + 1)
        if s.carrier_max_v > 0:
            frac = np.minimum(idx / self._glide_n, 1.0)
            f = self._freq_hz + (f1 - self._freq_hz) * frac
            a = self._amp_v + (a1 - self._amp_v) * frac
            self._freq_hz = float(f[-1])
            self._amp_v = float(a[-1])
            phase = self._phase + 2 * np.pi * np.cumsum(f) / self.fs
            self._phase = float(phase[-1] % (2 * np.pi))
            screen = a * np.sin(phase)
        else:
            screen = np.zeros(n)
        piezo = np.zeros(n)

        if p is not None and env is not None:
            e = env.block(n)
            if p.freq_hz > 0:
                ph = self._pulse_phase + 2 * np.pi * p.freq_hz * idx / self.fs
                self._pulse_phase = float(ph[-1] % (2 * np.pi))
                if p.shape == "square":
                    wave: np.ndarray | float = smooth_square(ph, p.edge_ms * 1e-3 * p.freq_hz)
                else:
                    wave = np.sin(ph)
            else:
                wave = self._polarity
            if p.channel == "screen":
                screen = screen * (1.0 - e) + p.peak_v * e * wave
            else:
                piezo = p.peak_v * e * wave

        g = self._master.block(n)
        self.samples_out += n
        if stop and not self._master.active:
            self._done = True
        pk, sk = self._peak_v["piezo"], self._peak_v["screen"]
        return np.clip(piezo * g, -pk, pk), np.clip(screen * g, -sk, sk)


__all__ = [
    "CHANNELS",
    "SHAPES",
    "Envelope",
    "PulseSpec",
    "StreamSink",
    "StreamSpec",
    "StreamSynth",
    "declared_peak_v",
    "smooth_square",
    "spec_problem",
]
