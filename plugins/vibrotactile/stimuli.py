"""Stimuli as output plans (volts at the piezo): flow between two points, a pulse at one.

Flow (paper Fig. 9): part 1 drives the (active -> passive) table entry, part 2 the
(passive -> active) one, each a sine at its table frequency on its actuator, with
linear ramps at both ends (so every segment starts and ends at 0 V) and the relay
switch in the silent gap between the two segments. Amplitudes are equalised in
sensation level at each part's active point: ``V = 10^((T(f) + SL)/20) / |H(f)|`` with T
the fingertip threshold (dB re 1 um), SL the common level (target, lowered until both
parts fit the drive limit).

The silence between the parts is ``gap_s`` (plus the relay guard the gate adds); with
``ringdown_gap_k`` > 0 it is at least ``k`` decay times of part 1's mode
(``plugins.vibrotactile.ringdown``), so part 1 no longer rings into part 2.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from console.plugin_api import (
    MAX_PLAN_S,
    OutputPlan,
    Segment,
    UserError,
    check_duration,
    patches_of,
    plan_samples,
)
from plugins.vibrotactile.interp import interpolate
from plugins.vibrotactile.ringdown import ringdown_gap_s
from plugins.vibrotactile.tables import Tables, query_indices, query_points, usable_bins
from plugins.vibrotactile.thresholds import Perception

Point = int | tuple[float, float]  # map point index, or (x, y) mm


@dataclass(frozen=True)
class StimulusSettings:
    sample_rate_hz: int = 48000
    part_s: float = 1.5
    ramp_ms: float = 100.0
    gap_s: float = 0.0
    pulse_s: float = 0.5
    sensation_level_db: float = 20.0
    drive_max_v: float = 95.0  # amplitude cap; also capped by the piezo limits
    interpolation: str = "spline"
    ringdown_gap_k: float = 0.0  # 0: no ring-down gap (the paper's flow)
    ringdown_zeta: float = 0.0  # 0: damping from the map's half-power bandwidth


def tone_segment(
    freq_hz: float,
    amp_v: float,
    duration_s: float,
    ramp_s: float,
    sample_rate_hz: int,
    patches: frozenset[str],
    label: str = "",
) -> Segment:
    """Sine at ``freq_hz`` with linear ramps: exactly 0 V at the first and last sample."""
    n = plan_samples(duration_s, sample_rate_hz, what=label or "tone")
    nr = max(1, int(round(ramp_s * sample_rate_hz)))
    if n < 2 * nr + 1:
        raise UserError(
            f"stimulus of {duration_s:g} s is shorter than its two {ramp_s * 1e3:g} ms ramps"
        )
    t = np.arange(n) / sample_rate_hz
    env = np.ones(n)
    env[:nr] = np.arange(nr) / nr
    env[-nr:] = np.arange(nr)[::-1] / nr
    v = amp_v * env * np.sin(2 * np.pi * freq_hz * t)
    return Segment(piezo_v=v, screen_v=np.zeros(n), patches=patches, label=label)


def _choice(t: Tables, a: Point, b: Point, method: str) -> dict:
    """Table answer for a (index or mm) pair plus |H| at the active point (um/V)."""

    m = t.vmap
    xy = [
        m.points_mm[p] if isinstance(p, (int, np.integer)) else np.asarray(p, float) for p in (a, b)
    ]
    if np.allclose(xy[0], xy[1]):
        raise UserError("--from and --to are the same point: a flow needs two different points")
    if isinstance(a, (int, np.integer)) and isinstance(b, (int, np.integer)):
        ans = query_indices(t, int(a), int(b))
        h_a = m.frf_um_per_v[:, int(a)]
        h_b = m.frf_um_per_v[:, int(b)]
    else:
        ans = query_points(t, tuple(xy[0]), tuple(xy[1]), method=method)
        h = interpolate(m, np.array(xy), method)
        h_a, h_b = h[:, 0], h[:, 1]
    e = m.excitation_index(ans["actuator"])
    k = usable_bins(m, t.band_hz)[
        np.argmin(np.abs(m.freq_hz[usable_bins(m, t.band_hz)] - ans["frequency_hz"]))
    ]
    ans["active_um_per_v"] = float(abs(h_a[e, k]))
    ans["passive_um_per_v"] = float(abs(h_b[e, k]))
    ans["contrast_db"] = float(
        20 * np.log10(max(ans["active_um_per_v"], 1e-30) / max(ans["passive_um_per_v"], 1e-30))
    )
    return ans


def gap_after_part_1(m, part1: dict, settings: StimulusSettings, band_hz: float) -> dict:
    """The silence between the parts: ``settings.gap_s``, or with ``ringdown_gap_k`` > 0
    at least ``k`` decay times of part 1's mode (``ringdown`` says which and why)."""
    out = {"gap_s": float(settings.gap_s)}
    if settings.ringdown_gap_k > 0:
        rd = ringdown_gap_s(
            m,
            part1["actuator"],
            part1["frequency_hz"],
            settings.ringdown_gap_k,
            zeta=settings.ringdown_zeta,
            band_hz=band_hz,
        )
        out = {
            "gap_s": max(out["gap_s"], rd["gap_s"]),
            "ringdown": {**rd, "k": settings.ringdown_gap_k},
        }
    return out


def drive_cap_v(settings: StimulusSettings, piezo_min_v: float, piezo_max_v: float) -> float:
    """Largest sine amplitude allowed: the setting and both piezo limits."""
    return float(min(settings.drive_max_v, -piezo_min_v, piezo_max_v))


def flow_plan(
    t: Tables,
    a: Point,
    b: Point,
    perception: Perception,
    settings: StimulusSettings,
    *,
    piezo_min_v: float = -100.0,
    piezo_max_v: float = 250.0,
    max_plan_s: float = MAX_PLAN_S,
    name: str = "",
) -> OutputPlan:
    """Two-part flow from ``a`` to ``b`` (paper Fig. 9), equal sensation level in both
    parts; refused before its arrays are built when longer than ``max_plan_s``."""
    parts = [_choice(t, a, b, settings.interpolation), _choice(t, b, a, settings.interpolation)]
    cap = drive_cap_v(settings, piezo_min_v, piezo_max_v)
    for p in parts:
        if p["active_um_per_v"] <= 0 or p["max_difference_um_per_v"] <= 0:
            raise UserError(
                f"no frequency makes the active point vibrate more than the passive one "
                f"({p['actuator']}); pick other points"
            )
        p["threshold_db"] = float(perception.threshold_db(p["frequency_hz"], "fingertip"))
        p["max_sl_db"] = float(20 * np.log10(p["active_um_per_v"] * cap) - p["threshold_db"])
    sl = min(settings.sensation_level_db, *(p["max_sl_db"] for p in parts))
    gap = gap_after_part_1(t.vmap, parts[0], settings, t.band_hz)
    why = ""
    if "ringdown" in gap:
        why = f" (ring-down gap of ringdown_gap_k = {settings.ringdown_gap_k:g} decay times)"
    check_duration(
        2 * settings.part_s + gap["gap_s"], max_plan_s, f"{name or 'flow'}: parts and gap{why}"
    )
    segs = []
    for i, p in enumerate(parts):
        amp = 10 ** ((p["threshold_db"] + sl) / 20) / p["active_um_per_v"]
        p["amplitude_v"] = float(min(amp, cap))
        p["passive_sl_db"] = float(
            20 * np.log10(max(p["passive_um_per_v"] * amp, 1e-12)) - p["threshold_db"]
        )
        segs.append(
            tone_segment(
                p["frequency_hz"],
                p["amplitude_v"],
                settings.part_s,
                settings.ramp_ms / 1e3,
                settings.sample_rate_hz,
                patches_of(p["actuator"]),
                label=f"part {i + 1} {p['actuator']}",
            )
        )
    notes = []
    if sl < 3 * perception.jnd_db:
        notes.append(
            f"sensation level only {sl:.1f} dB (drive limit {cap:g} V): may be hard to feel"
        )
    if t.min_contrast_db > 0:
        short = [p for p in parts if p["contrast_db"] < t.min_contrast_db]
        notes += [
            f"part {parts.index(p) + 1}: contrast {p['contrast_db']:.1f} dB is below the "
            f"{t.min_contrast_db:g} dB floor (no candidate reaches it)"
            for p in short
        ]
    meta = {"kind": "flow", "sensation_level_db": float(sl), "parts": parts, "notes": notes}
    meta["method"] = "paper"
    meta["predicted_contrast_db"] = float(min(p["contrast_db"] for p in parts))
    meta["min_contrast_db"] = float(t.min_contrast_db)
    meta["rule"] = t.rule
    if "ringdown" in gap:
        meta["ringdown"] = gap["ringdown"]
    return OutputPlan(
        sample_rate_hz=settings.sample_rate_hz,
        segments=tuple(segs),
        name=name or "flow",
        gap_s=gap["gap_s"],
        meta=meta,
    )


def point_plan(
    t: Tables,
    a: Point,
    perception: Perception,
    settings: StimulusSettings,
    *,
    piezo_min_v: float = -100.0,
    piezo_max_v: float = 250.0,
    max_plan_s: float = MAX_PLAN_S,
    name: str = "",
) -> OutputPlan:
    """A localized pulse at one point: the excitation and frequency where its
    displacement per volt is largest (paper 4.1), at the target sensation level."""

    m = t.vmap
    keep = usable_bins(m, t.band_hz)
    h = (
        m.frf_um_per_v[:, int(a)]
        if isinstance(a, (int, np.integer))
        else interpolate(m, np.asarray([a], float), settings.interpolation)[:, 0]
    )
    amp = np.abs(h[:, keep])
    e, k = np.unravel_index(int(np.argmax(amp)), amp.shape)
    f = float(m.freq_hz[keep][k])
    g = float(amp[e, k])
    others = np.abs(m.frf_um_per_v[e, :, keep[k]])
    cap = drive_cap_v(settings, piezo_min_v, piezo_max_v)
    thr = float(perception.threshold_db(f, "fingertip"))
    sl = min(settings.sensation_level_db, 20 * np.log10(g * cap) - thr)
    v = float(min(10 ** ((thr + sl) / 20) / g, cap))
    check_duration(settings.pulse_s, max_plan_s, f"{name or 'point'}: pulse")
    seg = tone_segment(
        f,
        v,
        settings.pulse_s,
        min(settings.ramp_ms / 1e3, settings.pulse_s / 4),
        settings.sample_rate_hz,
        patches_of(m.excitations[e]),
        label=f"excitation {m.excitations[e]}",
    )
    return OutputPlan(
        sample_rate_hz=settings.sample_rate_hz,
        segments=(seg,),
        name=name or "point",
        meta={
            "kind": "point",
            "frequency_hz": f,
            "actuator": m.excitations[e],
            "amplitude_v": v,
            "um_per_v": g,
            "sensation_level_db": float(sl),
            "median_grid_um_per_v": float(np.median(others)),
        },
    )


def plan_to_wav(plan: OutputPlan, path, *, volts_full_scale: float, guard_s: float = 0.01) -> None:
    """Sound-card signal (float32, L piezo / R screen) = volts at actuator / ``volts_full_scale``
    (amplifier gain x sound-card full scale), segments separated by ``gap_s + guard_s`` silence."""
    from scipy.io import wavfile

    gap = np.zeros((int(round((plan.gap_s + guard_s) * plan.sample_rate_hz)), 2))
    blocks = []
    for i, s in enumerate(plan.segments):
        if i:
            blocks.append(gap)
        blocks.append(np.column_stack([s.piezo_v, s.screen_v]))
    data = (np.concatenate(blocks) / volts_full_scale).astype(np.float32)
    if np.abs(data).max() > 1.0:
        raise UserError(
            f"{path}: the plan exceeds the sound card's full scale ({volts_full_scale:g} V at the actuator)"
        )
    wavfile.write(str(path), plan.sample_rate_hz, data)
