"""The scope tap: the last seconds of what the gate handed the driver, per channel.

``ScopeTap.write(out, clock)`` runs on the audio thread after every block: it copies the
block's columns (sound-card units, as the driver got them) into a ring allocated up front,
so the callback allocates no buffer. ``ScopeTap.read(seconds)`` copies the newest samples
out and scales each channel to volts at its actuator (a ``ScopeTrace``). Channel-count
agnostic: the ring has one column per channel named at construction.
"""

from __future__ import annotations

import threading
from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np

#: seconds the ring keeps by default
SCOPE_SECONDS = 4.0


@dataclass(frozen=True)
class ScopeTrace:
    """``volts`` (n, C) at the actuators, sample ``k`` at gate clock ``clock + k``."""

    volts: np.ndarray
    sample_rate_hz: int
    clock: int  # gate clock (samples handed to the driver) of the first row
    channels: tuple[str, ...]
    #: (gate clock, kind, message) of the gate's events inside the trace (e-stop, switch)
    marks: tuple[tuple[int, str, str], ...] = ()

    @property
    def n(self) -> int:
        return int(self.volts.shape[0])

    def t_ms(self) -> np.ndarray:
        """Each row's time in ms, 0 at the newest sample (negative: in the past)."""
        return (np.arange(self.n) - (self.n - 1)) * (1e3 / self.sample_rate_hz)

    def peak_v(self) -> dict[str, float]:
        """Largest |volts| per channel over the trace."""
        if self.n == 0:
            return dict.fromkeys(self.channels, 0.0)
        peaks = np.max(np.abs(self.volts), axis=0)
        return {name: float(p) for name, p in zip(self.channels, peaks, strict=True)}

    def span(self, start: int, end: int) -> ScopeTrace:
        """The part from gate clock ``start`` to ``end`` (clipped to what is kept)."""
        a = min(max(start - self.clock, 0), self.n)
        b = min(max(end - self.clock, a), self.n)
        c0, c1 = self.clock + a, self.clock + b
        marks = tuple(m for m in self.marks if c0 <= m[0] < c1)
        return ScopeTrace(self.volts[a:b], self.sample_rate_hz, c0, self.channels, marks)

    def last(self, seconds: float) -> ScopeTrace:
        """The newest ``seconds`` of the trace."""
        end = self.clock + self.n
        return self.span(end - int(round(seconds * self.sample_rate_hz)), end)

    def silent_after(self, clock: int) -> tuple[float, float] | None:
        """From gate clock ``clock`` (an e-stop): (largest |volts| then, ms until every
        channel is zero), or None when the trace does not reach silence after it."""
        k = clock - self.clock
        if not 0 <= k < self.n:
            return None
        loud = np.flatnonzero(np.any(self.volts[k:] != 0.0, axis=1))
        end = 0 if loud.size == 0 else int(loud[-1]) + 1
        if k + end >= self.n:  # still sounding at the newest sample
            return None
        start_v = float(np.max(np.abs(self.volts[max(k - 1, 0)])))
        return start_v, end * 1e3 / self.sample_rate_hz


class ScopeTap:
    """A ring of the last ``seconds`` of driver blocks, one column per channel.

    ``volts_per_unit[c]`` turns channel ``c``'s sound-card units into volts at its
    actuator. One writer (the audio thread), any number of readers."""

    def __init__(
        self,
        sample_rate_hz: int,
        channels: Sequence[str],
        volts_per_unit: Sequence[float],
        seconds: float = SCOPE_SECONDS,
    ) -> None:
        if len(channels) != len(volts_per_unit):
            raise ValueError("one volts_per_unit per channel")
        self.sample_rate_hz = int(sample_rate_hz)
        self.channels = tuple(channels)
        self._scale = np.asarray(volts_per_unit, np.float64)
        self._cap = max(1, int(round(seconds * self.sample_rate_hz)))
        self._ring = np.empty((self._cap, len(self.channels)), np.float32)
        self._ring.fill(0.0)  # touch every page now, not on the audio thread
        self._written = 0  # rows written since the start
        self._clock_end = 0  # gate clock just after the newest row
        self._lock = threading.Lock()

    @property
    def capacity(self) -> int:
        return self._cap

    def write(self, out: np.ndarray, clock: int) -> None:
        """Copy block ``out`` (frames, C) whose first sample has gate clock ``clock``."""
        n = out.shape[0]
        cols = min(out.shape[1], self._ring.shape[1])
        if n > self._cap:  # a block longer than the ring: keep its end
            out, clock, n = out[n - self._cap :], clock + n - self._cap, self._cap
        ring = self._ring
        with self._lock:
            i = self._written % self._cap
            first = min(n, self._cap - i)
            ring[i : i + first, :cols] = out[:first, :cols]
            if first < n:
                ring[: n - first, :cols] = out[first:, :cols]
            self._written += n
            self._clock_end = clock + n

    def read(self, seconds: float | None = None) -> ScopeTrace:
        """The newest ``seconds`` (all kept when None) in volts at the actuators."""
        want = self._cap if seconds is None else int(round(seconds * self.sample_rate_hz))
        with self._lock:
            n = max(0, min(want, self._written, self._cap))
            j = self._written % self._cap
            if n <= j:
                raw = self._ring[j - n : j].copy()
            else:
                raw = np.concatenate([self._ring[self._cap - (n - j) :], self._ring[:j]])
            clock = self._clock_end - n
        volts = raw.astype(np.float64) * self._scale
        return ScopeTrace(volts, self.sample_rate_hz, clock, self.channels)
