"""The knob's feedback conditions, as a live stream described by parameters.

Conditions (paper 5.4 and its discussion), as ``<detent>[+<friction>]``:

* ``V``      silence;
* ``HD``     a square detent pulse on the screen at each sector crossing;
* ``HD+CF``  plus a 100 Vpp 180 Hz sine while the knob is held (constant friction);
* ``HD+VF``  plus a 100 Vpp sine whose frequency follows |angular velocity|, 60-180 Hz;
* ``HD+BF``  variant: a 180 Hz sine whose amplitude rises toward the sector boundaries;
* ``VD+CF``, ``VD+VF``, ``VD+BF`` variant: the detent is a vibrotactile burst on the piezo
  channel while the friction stays on the screen channel (both modalities at once).

The samples are synthesised by ``console.signals.stream_synth``: ``KnobStream`` describes its
condition once as a ``StreamSpec`` (the friction sine is the carrier, the detent its
pulse) and maps the knob's angle, velocity and touch to carrier targets, which it posts
with the crossings to its sink: a local ``StreamSynth`` (offline rendering), or, after
``bind()``, the outputs process's synth (where no plugin code runs). Click-free
by construction: the sine's phase is accumulated (never reset), frequency and amplitude
glide over ``glide_ms``; pulses are shaped by raised-cosine edges; a detent ducks the
friction sine (a convex mix, so the peak never exceeds the larger of the two); the whole
stream starts and stops with ``ramp_ms`` raised-cosine ramps. A crossing posted with
``post()`` (thread-safe) starts its detent at the first sample of the next block. Pulses
alternate polarity (no net charge); a crossing during a pulse extends it without a jump.
"""

from __future__ import annotations

import math
import threading
from collections import deque
from collections.abc import Mapping
from dataclasses import dataclass
from typing import Any

import numpy as np

from console.plugin_api import (
    Envelope,
    PulseSpec,
    StreamSink,
    StreamSpec,
    StreamSynth,
    UserError,
    patches_of,
    smooth_square,
    spec_problem,
)

from .settings import KNOB_DEFAULTS

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


class KnobStream:
    """Live knob feedback: ``next_block(n) -> (piezo_v, screen_v)`` in volts at the actuator.

    Feed it with ``post(crossings=..., angle_deg=..., velocity_deg_s=..., touching=...)``
    from any thread. ``request_stop()`` ramps down; then ``next_block`` returns ``None``.

    It synthesises nothing itself: ``spec`` describes the stream, and ``post`` forwards
    the crossings' ids and the friction's carrier targets to its sink. By default that is
    a local ``StreamSynth`` (offline rendering: ``next_block``, ``samples_out``, ``done``,
    ``detent_log`` and ``trace`` are its). After ``bind(sink)`` they go to ``sink`` (the
    outputs process's handle of a synth built from ``spec``): the stream plays there,
    ``next_block`` raises ``RuntimeError``, and the local ``samples_out``, ``done``,
    ``detent_log`` and ``trace`` stay as they were (the outputs process keeps its own).
    """

    def __init__(
        self,
        condition: str | Condition,
        sample_rate_hz: int = 48000,
        settings: Mapping[str, Any] | None = None,
        limits: Mapping[str, float] | None = None,
        sectors: int | None = None,
    ) -> None:
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

        # a raised cosine of length L stays under the gate's linear ramp of length R
        # (at full scale) when L >= pi/2 R: its steepest slope is pi / (2 L)
        ramp_min = max(float(lim.get("ramp_min_ms", 5.0)), 5.0)
        # the gate counts its ramp in whole samples (rounded): never fall short of that
        ramp_min = max(ramp_min, max(1, round(ramp_min * 1e-3 * self.fs)) * 1e3 / self.fs)
        try:
            self._spec = self._make_spec(max(float(s["ramp_ms"]), math.pi / 2 * ramp_min))
        except ValueError as e:
            raise UserError(f"[knob] {c.name}: {e}") from None
        why = spec_problem(
            self._spec,
            piezo_lo_v=float(lim["piezo_min_v"]),
            piezo_hi_v=float(lim["piezo_max_v"]),
            screen_peak_v=float(lim["screen_max_vpp"]) / 2,
            ramp_min_ms=ramp_min,
            sample_rate_hz=self.fs,
        )
        if why is not None:
            raise UserError(f"[knob] {c.name}: {why}")

        self._lock = threading.Lock()
        self._angle_deg = 0.0
        self._velocity_deg_s = 0.0
        self._touching = True
        self._next_id = 0
        self._synth = StreamSynth(self._spec)
        self._sink: StreamSink = self._synth
        self._sink.post((), *self._targets())

    def _make_spec(self, ramp_ms: float) -> StreamSpec:
        """The condition as parameters: the friction is the carrier, the detent its pulse."""
        s, c = self.s, self.condition
        cf = float(s["cf_freq_hz"])
        lo_hz = hi_hz = start_hz = cf
        carrier_v = 0.0
        if c.friction in ("constant", "velocity"):
            carrier_v = float(s["carrier_vpp"]) / 2
        elif c.friction == "boundary":
            carrier_v = max(float(s["bf_max_vpp"]), float(s["bf_min_vpp"])) / 2
        if c.friction == "velocity":
            # the ends of _targets' mapping as it rounds them (a target clamped by an ulp
            # would shift the phase ever after)
            rest, speed = float(s["vf_freq_at_rest_hz"]), float(s["vf_freq_at_speed_hz"])
            at_speed = rest + 1.0 * (speed - rest)
            lo_hz, hi_hz, start_hz = min(rest, at_speed), max(rest, at_speed), rest
        pulse = None
        if c.detent == "screen":
            pulse = PulseSpec(
                "square",
                "screen",
                peak_v=float(s["detent_vpp"]) / 2,
                freq_hz=float(s["detent_freq_hz"]),
                length_ms=float(s["detent_ms"]),
                edge_ms=float(s["detent_edge_ms"]),
            )
        elif c.detent == "piezo":
            pulse = PulseSpec(
                "burst",
                "piezo",
                peak_v=float(s["vd_peak_v"]),
                freq_hz=float(s["vd_freq_hz"]),
                length_ms=float(s["vd_ms"]),
                edge_ms=0.0,
            )
        return StreamSpec(
            sample_rate_hz=self.fs,
            patches=self.patches,
            screen=self.screen,
            carrier_max_v=carrier_v,
            carrier_min_hz=lo_hz,
            carrier_max_hz=hi_hz,
            start_hz=start_hz,
            glide_ms=float(s["glide_ms"]),
            ramp_ms=ramp_ms,
            pulse=pulse,
        )

    @property
    def spec(self) -> StreamSpec:
        """The stream as parameters (``spec.to_json()`` for the outputs process)."""
        return self._spec

    def bind(self, sink: StreamSink) -> None:
        """Post to ``sink`` from now on (``post(ids, carrier_hz, carrier_v)``,
        ``request_stop()``: a synth of ``spec`` in the outputs process); it gets the
        current targets at once. Bind before the stream plays locally."""
        if not isinstance(sink, StreamSink):
            raise TypeError(f"bind: {type(sink).__name__} has no post() and request_stop()")
        if self._synth.samples_out:
            raise RuntimeError("bind: this stream already plays locally; bind a new one")
        with self._lock:
            self._sink = sink
            sink.post((), *self._targets())

    @property
    def bound(self) -> bool:
        """True after ``bind()``: the stream plays in the outputs process."""
        return self._sink is not self._synth

    # ------------------------------------------------------------------ inputs
    def post(
        self,
        crossings: int = 0,
        angle_deg: float | None = None,
        velocity_deg_s: float | None = None,
        touching: bool | None = None,
    ) -> list[int]:
        """Knob events from any thread; returns the ids given to the crossings."""
        with self._lock:
            ids = list(range(self._next_id, self._next_id + max(int(crossings), 0)))
            self._next_id += len(ids)
            if angle_deg is not None and math.isfinite(angle_deg):
                self._angle_deg = float(angle_deg)
            if velocity_deg_s is not None and math.isfinite(velocity_deg_s):
                self._velocity_deg_s = float(velocity_deg_s)
            if touching is not None:
                self._touching = bool(touching)
            # under the lock: targets reach the sink in the order they were computed
            self._sink.post(ids, *self._targets())
        return ids

    @property
    def done(self) -> bool:
        """True once the stream has ramped down after ``request_stop()`` (local only)."""
        return self._synth.done

    def request_stop(self) -> None:
        with self._lock:
            self._sink.request_stop()

    # ------------------------------------------------------------------ targets
    def _targets(self) -> tuple[float | None, float]:
        """(frequency Hz, amplitude V peak) the friction sine should have now; a
        frequency of ``None`` keeps the current one (the synth holds it while silent)."""
        s, c = self.s, self.condition
        if c.friction == "none" or not self._touching:
            return None, 0.0
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
    @property
    def samples_out(self) -> int:
        """Samples rendered locally."""
        return self._synth.samples_out

    @property
    def detent_log(self) -> deque[tuple[int, int]]:
        """(crossing id, sample index where its detent started or was extended): the local
        synth's, or, once bound to a sink that keeps one (the outputs process's stream),
        the sink's (assign a shorter deque to bound the local one)."""
        remote = getattr(self._sink, "detent_log", None) if self.bound else None
        return remote if remote is not None else self._synth.detent_log

    @detent_log.setter
    def detent_log(self, log: deque[tuple[int, int]]) -> None:
        self._synth.detent_log = log

    @property
    def trace(self) -> deque[tuple[int, float, float]]:
        """Per block: (first sample, target frequency Hz, target amplitude V); local
        rendering only (assign a shorter deque to bound it)."""
        return self._synth.trace

    @trace.setter
    def trace(self, log: deque[tuple[int, float, float]]) -> None:
        self._synth.trace = log

    def next_block(self, n: int) -> tuple[np.ndarray, np.ndarray] | None:
        if self.bound:
            raise RuntimeError(
                f"knob stream {self.condition.name}: it plays in the outputs process "
                "(bound to a remote synth); next_block renders only unbound streams"
            )
        return self._synth.next_block(n)


__all__ = [
    "CONDITIONS",
    "DETENTS",
    "FRICTIONS",
    "Condition",
    "Envelope",
    "KnobStream",
    "parse_condition",
    "smooth_square",
]
