"""The knob's feedback conditions, synthesized block by block (a ``StreamSource``).

Conditions (paper 5.4 and its discussion), as ``<detent>[+<friction>]``:

* ``V``      silence;
* ``HD``     a square detent pulse on the screen at each sector crossing;
* ``HD+CF``  plus a 100 Vpp 180 Hz sine while the knob is held (constant friction);
* ``HD+VF``  plus a 100 Vpp sine whose frequency follows |angular velocity|, 60-180 Hz;
* ``HD+BF``  variant: a 180 Hz sine whose amplitude rises toward the sector boundaries;
* ``VD+CF``, ``VD+VF``, ``VD+BF`` variant: the detent is a vibrotactile burst on the piezo
  channel while the friction stays on the screen channel (both modalities at once).

Click-free by construction: the sine's phase is accumulated (never reset), frequency and
amplitude glide linearly over ``glide_ms``; pulses are shaped by raised-cosine edges; a
detent ducks the friction sine (a convex mix, so the peak never exceeds the larger of
the two); the whole stream starts and stops with ``ramp_ms`` raised-cosine ramps.
A crossing posted with ``post()`` (thread-safe) starts its detent at the first sample of
the next block. Pulses alternate polarity (no net charge); a crossing during a pulse
extends it without a jump.
"""

from __future__ import annotations

import math
import threading
from collections import deque
from collections.abc import Mapping
from dataclasses import dataclass
from typing import Any

import numpy as np

from console.errors import UserError
from console.types import patches_of

DETENTS = {"HD": "screen", "VD": "piezo"}
FRICTIONS = {"CF": "constant", "VF": "velocity", "BF": "boundary"}
#: The paper's four conditions first, then the discussion's variants.
CONDITIONS = ("V", "HD", "HD+CF", "HD+VF", "HD+BF", "VD+CF", "VD+VF", "VD+BF")


@dataclass(frozen=True)
class Condition:
    name: str
    detent: str  # "none" | "screen" | "piezo"
    friction: str  # "none" | "constant" | "velocity" | "boundary"


def parse_condition(name: str) -> Condition:
    """``"HD+VF"`` -> Condition; ``UserError`` naming the known ones otherwise."""
    key = name.strip().upper()
    if key == "V":
        return Condition("V", "none", "none")
    parts = key.split("+")
    if parts[0] in DETENTS and len(parts) <= 2 and (len(parts) == 1 or parts[1] in FRICTIONS):
        return Condition(key, DETENTS[parts[0]], FRICTIONS[parts[1]] if len(parts) == 2 else "none")
    raise UserError(
        f"condition {name!r}: unknown knob condition; use one of {', '.join(CONDITIONS)}"
    )


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


class KnobStream:
    """Live knob feedback: ``next_block(n) -> (piezo_v, screen_v)`` in volts at the actuator.

    Feed it with ``post(crossings=..., angle_deg=..., velocity_deg_s=..., touching=...)``
    from any thread. ``request_stop()`` ramps down; then ``next_block`` returns ``None``.
    """

    def __init__(
        self,
        condition: str | Condition,
        sample_rate_hz: int = 48000,
        settings: Mapping[str, Any] | None = None,
        limits: Mapping[str, float] | None = None,
        sectors: int | None = None,
    ) -> None:
        from .settings import KNOB_DEFAULTS

        self.condition = (
            condition if isinstance(condition, Condition) else parse_condition(condition)
        )
        s = {**KNOB_DEFAULTS, **(settings or {})}
        lim = {
            "screen_max_vpp": 200.0,
            "piezo_min_v": -100.0,
            "piezo_max_v": 250.0,
            "ramp_min_ms": 5.0,
        }
        lim.update(limits or {})
        self.s, self.fs = s, int(sample_rate_hz)
        self.width_deg = 360.0 / int(sectors or s["sectors"])
        c = self.condition
        screen_vpp = 0.0
        if c.detent == "screen":
            screen_vpp = max(screen_vpp, s["detent_vpp"])
        if c.friction in ("constant", "velocity"):
            screen_vpp = max(screen_vpp, s["carrier_vpp"])
        if c.friction == "boundary":
            screen_vpp = max(screen_vpp, s["bf_max_vpp"], s["bf_min_vpp"])
        if screen_vpp > lim["screen_max_vpp"]:
            raise UserError(
                f"[knob] {c.name}: screen signal {screen_vpp:g} Vpp exceeds [limits] "
                f"screen_max_vpp = {lim['screen_max_vpp']:g}; lower carrier_vpp/detent_vpp/bf_max_vpp"
            )
        if c.detent == "piezo" and (
            s["vd_peak_v"] > lim["piezo_max_v"] or -s["vd_peak_v"] < lim["piezo_min_v"]
        ):
            raise UserError(
                f"[knob] vd_peak_v = {s['vd_peak_v']:g}: outside [limits] piezo_min_v.."
                f"piezo_max_v ({lim['piezo_min_v']:g}..{lim['piezo_max_v']:g}); lower vd_peak_v"
            )
        self.patches = patches_of(s["vd_excitation"]) if c.detent == "piezo" else frozenset()
        self.screen = c.detent == "screen" or c.friction != "none"

        ms = self.fs / 1000.0
        # a raised cosine of length L stays under the gate's linear ramp of length R
        # (at full scale) when L >= pi/2 R: its steepest slope is pi / (2 L)
        ramp_min = max(float(lim.get("ramp_min_ms", 5.0)), 5.0)
        ramp_ms = max(float(s["ramp_ms"]), math.pi / 2 * ramp_min)
        self._master = Envelope(round(ramp_ms * ms), None)
        self._master.trigger()
        self._master.k = -1.0  # the first sample is exactly zero (the gate's start rule)
        edge_n = max(round(s["detent_edge_ms"] * ms), 1)
        self._detent = Envelope(edge_n, max(round(s["detent_ms"] * ms) - 2 * edge_n, 0))
        vd_n = max(round(s["vd_ms"] * ms), 4)
        self._vd = Envelope(vd_n // 2, 0)  # a Hann-shaped burst (rise, then fall)
        self._glide_n = max(round(s["glide_ms"] * ms), 1)

        self._lock = threading.Lock()
        self._pending: deque[tuple[int, float]] = deque()  # (crossing id, direction)
        self._angle_deg = 0.0
        self._velocity_deg_s = 0.0
        self._touching = True
        self._stop = False
        self._done = False

        self._phase = 0.0
        self._detent_phase = 0.0
        self._vd_phase = 0.0
        self._freq_hz = float(s["cf_freq_hz"])
        self._freq_hz, _ = self._targets()
        self._amp_v = 0.0  # the master ramp and the glide start from silence
        self._polarity = 1.0
        self._next_id = 0
        self.samples_out = 0
        #: (crossing id, sample index where its detent started or was extended)
        self.detent_log: deque[tuple[int, int]] = deque(maxlen=100000)
        #: per block: (first sample, target frequency Hz, target amplitude V)
        self.trace: deque[tuple[int, float, float]] = deque(maxlen=100000)

    # ------------------------------------------------------------------ inputs
    def post(
        self,
        crossings: int = 0,
        angle_deg: float | None = None,
        velocity_deg_s: float | None = None,
        touching: bool | None = None,
    ) -> list[int]:
        """Knob events from any thread; returns the ids given to the crossings."""
        ids = []
        with self._lock:
            for _ in range(max(int(crossings), 0)):
                ids.append(self._next_id)
                self._pending.append((self._next_id, 1.0))
                self._next_id += 1
            if angle_deg is not None and math.isfinite(angle_deg):
                self._angle_deg = float(angle_deg)
            if velocity_deg_s is not None and math.isfinite(velocity_deg_s):
                self._velocity_deg_s = float(velocity_deg_s)
            if touching is not None:
                self._touching = bool(touching)
        return ids

    @property
    def done(self) -> bool:
        """True once the stream has ramped down after ``request_stop()``."""
        return self._done

    def request_stop(self) -> None:
        with self._lock:
            self._stop = True

    # ------------------------------------------------------------------ targets
    def _targets(self) -> tuple[float, float]:
        """(frequency Hz, amplitude V peak) the friction sine should have now."""
        s, c = self.s, self.condition
        if c.friction == "none" or not self._touching:
            return self._freq_hz, 0.0
        if c.friction == "constant":
            return s["cf_freq_hz"], s["carrier_vpp"] / 2
        if c.friction == "velocity":
            x = min(abs(self._velocity_deg_s) / s["vf_full_speed_deg_s"], 1.0)
            f = s["vf_freq_at_rest_hz"] + x * (s["vf_freq_at_speed_hz"] - s["vf_freq_at_rest_hz"])
            return f, s["carrier_vpp"] / 2
        r = self._angle_deg % self.width_deg
        closeness = 1.0 - 2.0 * min(r, self.width_deg - r) / self.width_deg
        vpp = s["bf_min_vpp"] + (s["bf_max_vpp"] - s["bf_min_vpp"]) * closeness ** s["bf_exponent"]
        return s["cf_freq_hz"], vpp / 2

    # ------------------------------------------------------------------ output
    def next_block(self, n: int) -> tuple[np.ndarray, np.ndarray] | None:
        if self._done:
            return None
        with self._lock:
            events = list(self._pending)
            self._pending.clear()
            stop = self._stop
            f1, a1 = self._targets()
        start = self.samples_out
        if stop:
            self._master.release()
        c = self.condition
        if events:
            if c.detent == "screen":
                if not self._detent.active:
                    self._polarity = -self._polarity
                self._detent.trigger()
            elif c.detent == "piezo":
                self._vd.trigger()
            for cid, _ in events:
                self.detent_log.append((cid, start))
        self.trace.append((start, f1, a1))

        idx = np.arange(1, n + 1)
        frac = np.minimum(idx / self._glide_n, 1.0)
        f = self._freq_hz + (f1 - self._freq_hz) * frac
        a = self._amp_v + (a1 - self._amp_v) * frac
        self._freq_hz = float(f[-1])
        self._amp_v = float(a[-1])
        phase = self._phase + 2 * np.pi * np.cumsum(f) / self.fs
        self._phase = float(phase[-1] % (2 * np.pi))
        screen = a * np.sin(phase)
        piezo = np.zeros(n)

        if c.detent == "screen":
            env = self._detent.block(n)
            if self.s["detent_freq_hz"] > 0:
                fd = self.s["detent_freq_hz"]
                ph = self._detent_phase + 2 * np.pi * fd * idx / self.fs
                self._detent_phase = float(ph[-1] % (2 * np.pi))
                edge_frac = self.s["detent_edge_ms"] * 1e-3 * fd
                pulse = smooth_square(ph, edge_frac)
            else:
                pulse = self._polarity
            screen = screen * (1.0 - env) + (self.s["detent_vpp"] / 2) * env * pulse
        elif c.detent == "piezo":
            env = self._vd.block(n)
            ph = self._vd_phase + 2 * np.pi * self.s["vd_freq_hz"] * idx / self.fs
            self._vd_phase = float(ph[-1] % (2 * np.pi))
            piezo = self.s["vd_peak_v"] * env * np.sin(ph)

        g = self._master.block(n)
        self.samples_out += n
        if stop and not self._master.active:
            self._done = True
        return piezo * g, screen * g
