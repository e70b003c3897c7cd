"""Limits per channel from the profile and the check every plan passes before it plays:
volts at the actuator, finite numbers, ramps at start and end, the slew limit for its routing
(dV/dt <= I / C), its length. A plan out of limits is refused, never clipped.

``Limits`` is deep-immutable: its fields cannot be assigned and the mappings inside it are
read-only views of private copies (``dataclasses.replace`` makes a new object)."""

from __future__ import annotations

import logging
import math
from collections.abc import Mapping
from dataclasses import dataclass, field, fields
from types import MappingProxyType
from typing import TYPE_CHECKING, Any

import numpy as np

from console.core.channels import BUS_CHANNELS, ChannelLayout
from console.core.errors import SafetyRefusal
from console.core.types import PATCHES, OutputPlan

if TYPE_CHECKING:
    from console.config.profile import Profile

log = logging.getLogger("haptable.safety")
RAMP_TOLERANCE = 1.02  # a sine under a linear envelope may touch the envelope


@dataclass(frozen=True)
class Limits:
    """Per-channel limits in volts at the actuator, and the timing rules.

    Deep-immutable: assigning a field raises ``FrozenInstanceError``; ``patch_capacitance_f``
    and ``patch_relay`` are read-only mappings over private copies (an item assignment
    raises ``TypeError``, and changing the dict a caller passed in changes nothing here);
    ``channels`` is a tuple."""

    sample_rate_hz: int
    piezo_min_v: float
    piezo_max_v: float
    screen_max_v: float  # peak, = screen_max_vpp / 2
    piezo_card_v: float  # the largest |volts| the sound card + amplifier can produce
    screen_card_v: float
    rating_vpp: float
    ramp_samples: int
    max_plan_samples: int
    guard_samples: int
    settle_samples: int  # switch time + guard after a switch
    estop_timeout_s: float
    # slew: dV/dt = I / C, per amplifier and per relay channel
    piezo_current_a: float = 0.2
    screen_current_a: float = 0.2
    relay_current_a: float = 0.1
    patch_capacitance_f: Mapping[str, float] = field(default_factory=dict)
    patch_relay: Mapping[str, int] = field(default_factory=dict)
    screen_capacitance_f: float = 200e-9
    min_switch_interval_samples: int = 0
    #: what each sound-card channel drives (``[audio] channels``)
    channels: tuple[str, ...] = BUS_CHANNELS

    def __post_init__(self) -> None:
        caps = {str(p): float(c) for p, c in dict(self.patch_capacitance_f).items()}
        relays = {str(p): int(c) for p, c in dict(self.patch_relay).items()}
        object.__setattr__(self, "patch_capacitance_f", MappingProxyType(caps))
        object.__setattr__(self, "patch_relay", MappingProxyType(relays))
        object.__setattr__(self, "channels", tuple(str(c) for c in self.channels))

    def __reduce__(self) -> tuple[Any, ...]:
        """Pickle and copy by the field values (a read-only mapping does not pickle)."""
        values = {f.name: vars(self)[f.name] for f in fields(self)}
        for name in ("patch_capacitance_f", "patch_relay"):
            values[name] = dict(values[name])
        return _limits_from_fields, (type(self), values)

    @classmethod
    def from_profile(cls, profile: Profile) -> Limits:
        fs = int(profile.get("audio.sample_rate_hz"))
        full = float(profile.get("audio.full_scale_v"))
        guard = profile.get("relays.guard_ms") * 1e-3
        switch = profile.get("relays.switch_time_ms") * 1e-3
        patches = profile.items("patches")
        return cls(
            sample_rate_hz=fs,
            piezo_min_v=float(profile.get("limits.piezo_min_v")),
            piezo_max_v=float(profile.get("limits.piezo_max_v")),
            screen_max_v=float(profile.get("limits.screen_max_vpp")) / 2,
            piezo_card_v=full * float(profile.get("amplifiers.piezo_gain")),
            screen_card_v=full * float(profile.get("amplifiers.screen_gain")),
            rating_vpp=float(profile.get("relays.rating_vpp")),
            ramp_samples=max(1, round(profile.get("limits.ramp_min_ms") * 1e-3 * fs)),
            max_plan_samples=round(profile.get("limits.max_plan_s") * fs),
            guard_samples=round(guard * fs),
            settle_samples=round((guard + switch) * fs),
            estop_timeout_s=profile.get("limits.estop_timeout_ms") * 1e-3,
            piezo_current_a=float(profile.get("amplifiers.piezo_peak_current_ma")) * 1e-3,
            screen_current_a=float(profile.get("amplifiers.screen_peak_current_ma")) * 1e-3,
            relay_current_a=float(profile.get("relays.current_rating_ma")) * 1e-3,
            patch_capacitance_f={n: float(p["capacitance_nf"]) * 1e-9 for n, p in patches.items()},
            patch_relay={
                n: int(p["relay_channel"]) for n, p in patches.items() if p.get("relay_channel")
            },
            screen_capacitance_f=float(profile.get("screen.capacitance_nf")) * 1e-9,
            min_switch_interval_samples=round(
                profile.get("relays.min_switch_interval_ms") * 1e-3 * fs
            ),
            channels=ChannelLayout.from_profile(profile).names,
        )

    @property
    def layout(self) -> ChannelLayout:
        return ChannelLayout(self.channels)

    def column_steps_v(self, connected: frozenset[str]) -> np.ndarray:
        """The slew limit of every channel as the largest change per sample, in volts:
        the bus's for the ``connected`` patches, a patch channel's for its patch alone,
        the screen's."""
        steps = []
        for name in self.channels:
            if name == "screen":
                steps.append(self.max_step_v("screen"))
            elif name == "piezo":
                steps.append(self.max_step_v("piezo", connected))
            else:
                steps.append(self.max_step_v("piezo", frozenset({name})))
        return np.array(steps)

    def column_ranges(self) -> list[tuple[float, float]]:
        """Allowed volts per channel: piezo limits on the bus and patch channels, the
        screen's on the screen channel."""
        return [
            self.screen_range() if name == "screen" else self.piezo_range()
            for name in self.channels
        ]

    def slew_v_per_s(self, channel: str, patches: frozenset[str] = frozenset()) -> float:
        """Fastest change the channel may make: the amplifier's peak current into every
        load it drives, and each relay channel's current rating into the loads behind it."""
        if channel == "screen":
            c = self.screen_capacitance_f
            return min(self.screen_current_a, self.relay_current_a) / c
        caps = self.patch_capacitance_f or {p: 90e-9 for p in PATCHES}
        chosen = [p for p in patches if p in caps] or [max(caps, key=caps.__getitem__)]
        per_relay: dict[int | str, float] = {}
        for p in chosen:
            ch = self.patch_relay.get(p, p)
            per_relay[ch] = per_relay.get(ch, 0.0) + caps[p]
        total = sum(caps[p] for p in chosen)
        return min(self.piezo_current_a / total, self.relay_current_a / max(per_relay.values()))

    def max_step_v(self, channel: str, patches: frozenset[str] = frozenset()) -> float:
        """The slew limit as the largest change from one sample to the next, in volts."""
        return self.slew_v_per_s(channel, patches) / self.sample_rate_hz

    def piezo_range(self) -> tuple[float, float]:
        return max(self.piezo_min_v, -self.piezo_card_v), min(self.piezo_max_v, self.piezo_card_v)

    def screen_range(self) -> tuple[float, float]:
        peak = min(self.screen_max_v, self.screen_card_v)
        return -peak, peak


def _limits_from_fields(cls: type[Limits], values: dict[str, Any]) -> Limits:
    """``Limits`` from its field values (``Limits.__reduce__``)."""
    return cls(**values)


def range_problem(x: np.ndarray, lo: float, hi: float, rating_vpp: float) -> str | None:
    bad = np.flatnonzero(~np.isfinite(x))
    if bad.size:
        return f"NaN/inf at sample {int(bad[0])}"
    if x.size == 0:
        return None
    mn, mx = float(x.min()), float(x.max())
    if mn < lo - 1e-9 or mx > hi + 1e-9:
        k = int(np.argmax((x < lo - 1e-9) | (x > hi + 1e-9)))
        return f"{x[k]:.1f} V at sample {k} is outside {lo:g}..{hi:g} V"
    if mx - mn > rating_vpp + 1e-9:
        return f"{mx - mn:.1f} Vpp exceeds the relay rating {rating_vpp:g} Vpp"
    return None


def slew_problem(x: np.ndarray, prev: float, max_step: float, *, end: bool) -> str | None:
    """A change from one sample to the next (from ``prev``; to 0 after the end when
    ``end``) larger than ``max_step`` volts."""
    if x.size == 0:
        return None
    d = np.abs(np.diff(x, prepend=prev, append=0.0 if end else x[-1]))
    tol = max_step * 1e-9 + 1e-9
    over = np.flatnonzero(d > max_step + tol)
    if not over.size:
        return None
    k = int(over[0])
    return (
        f"steps {float(d[k]):.2f} V in one sample at sample {k}, over its slew limit of "
        f"{max_step:.2f} V per sample (amplifier/relay current into the load capacitance); "
        f"smooth the edge"
    )


def _ramp_problem(x: np.ndarray, ramp: int) -> str | None:
    """Start and end at zero, under a linear envelope ``ramp`` samples long."""
    peak = float(np.max(np.abs(x))) if x.size else 0.0
    if peak == 0.0:
        return None
    tol = 1e-6 * peak + 1e-9
    if abs(x[0]) > tol or abs(x[-1]) > tol:
        which = "start" if abs(x[0]) > tol else "end"
        return f"does not {which} at zero ({x[0] if which == 'start' else x[-1]:.3g} V)"
    n = min(ramp, x.size)
    env = peak * (np.arange(n) / ramp) * RAMP_TOLERANCE + tol
    head, tail = np.abs(x[:n]), np.abs(x[::-1][:n])
    for part, seg in (("start", head), ("end", tail)):
        over = np.flatnonzero(seg > env)
        if over.size:
            return (
                f"rises faster than a {ramp}-sample ramp at its {part} "
                f"(sample {int(over[0])} of the {part}); add a linear ramp"
            )
    return None


def check_plan(plan: OutputPlan, limits: Limits) -> None:
    """Refuse a plan the outputs must not play. Raises ``SafetyRefusal``."""
    name = plan.name or "plan"
    gap_s = plan.gap_s
    if not isinstance(gap_s, (int, float)) or not math.isfinite(gap_s) or gap_s < 0:
        raise SafetyRefusal(f"{name}: gap_s = {gap_s!r}: must be a finite number of seconds >= 0")
    n_total = sum(int(np.size(getattr(seg, "piezo_v", ()))) for seg in plan.segments)
    n_total += round(gap_s * limits.sample_rate_hz) * max(len(plan.segments) - 1, 0)
    if n_total > limits.max_plan_samples:
        raise SafetyRefusal(
            f"{name}: {n_total / limits.sample_rate_hz:.1f} s is longer than [limits] max_plan_s"
        )
    if plan.sample_rate_hz != limits.sample_rate_hz:
        raise SafetyRefusal(
            f"{name}: sample rate {plan.sample_rate_hz} Hz, but the output runs at "
            f"{limits.sample_rate_hz} Hz; render it at [audio] sample_rate_hz"
        )
    if not plan.segments:
        raise SafetyRefusal(f"{name}: no segments to play")
    total = 0
    layout = limits.layout
    for i, seg in enumerate(plan.segments, 1):
        label = f"{name}: segment {i}" + (f" ({seg.label})" if seg.label else "")
        total += _check_segment(seg, label, layout, limits)
    if total > limits.max_plan_samples:
        raise SafetyRefusal(
            f"{name}: {total / limits.sample_rate_hz:.1f} s is longer than [limits] max_plan_s"
        )


def _check_segment(seg, label: str, layout: ChannelLayout, limits: Limits) -> int:
    """Refuse a segment the outputs must not play; its length in samples."""
    unknown = set(seg.patches) - set(PATCHES)
    if unknown:
        raise SafetyRefusal(f"{label}: unknown patches {sorted(unknown)}; use {PATCHES}")
    given = {"piezo_v": seg.piezo_v, "screen_v": seg.screen_v}
    given.update({f"patch_v[{p!r}]": v for p, v in seg.patch_v.items()})
    for what, v in given.items():
        a = np.asarray(v)
        if a.ndim != 1 or not np.issubdtype(a.dtype, np.number):
            raise SafetyRefusal(f"{label}: {what} must be a 1-D array of volts")
        if a.size != np.size(seg.piezo_v):
            raise SafetyRefusal(f"{label}: piezo and screen channels differ in length")
    try:
        raw = layout.columns(seg)
    except ValueError as exc:
        raise SafetyRefusal(f"{label}: {exc}") from None
    arrays = [np.asarray(a).astype(float, copy=False) for a in raw]
    n = arrays[layout.screen_index].size
    patches = frozenset(seg.patches)
    steps = limits.column_steps_v(patches)
    # the screen last, as the two-channel check always did
    order = sorted(range(layout.n), key=lambda k: layout.names[k] == "screen")
    ranges = limits.column_ranges()
    for k in order:
        x, chan = arrays[k], layout.names[k]
        lo, hi = ranges[k]
        if (p := range_problem(x, lo, hi, limits.rating_vpp)) is not None:
            raise SafetyRefusal(f"{label}: {chan} channel {p}")
        if (p := _ramp_problem(x, limits.ramp_samples)) is not None:
            raise SafetyRefusal(f"{label}: {chan} channel {p}")
        if (p := slew_problem(x, 0.0, float(steps[k]), end=True)) is not None:
            raise SafetyRefusal(f"{label}: {chan} channel {p}")
    piezo_on = any(np.any(arrays[k]) for k, c in enumerate(layout.names) if c != "screen")
    if (piezo_on or np.any(seg.piezo_v)) and not seg.patches:
        raise SafetyRefusal(f"{label}: piezo signal with no patch selected")
    if np.any(seg.piezo_v) and not seg.patches - set(seg.patch_v):
        raise SafetyRefusal(
            f"{label}: piezo_v reaches no patch (each of {sorted(seg.patches)} has its own "
            f"drive in patch_v); put it in patch_v or add its patches"
        )
    if np.any(arrays[layout.screen_index]) and not seg.screen:
        raise SafetyRefusal(f"{label}: screen signal with the screen relay open")
    return n
