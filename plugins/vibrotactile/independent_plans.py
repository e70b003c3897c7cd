"""Output plans with a drive per patch: the ``independent`` (and ``time_reversal``)
methods of the ``flow`` and ``point`` effects (``plugins.vibrotactile.independent``).

A part plays ``V |x_p| env(t) sin(2 pi f t + arg x_p)`` on each patch p (``x`` scaled to
1 on its strongest patch, so no patch exceeds ``V``), with the effects' linear ramps,
as a ``Segment.per_patch``: a profile must give each patch its own ``[audio]`` channel.
A flow's two parts play at the same sensation level at their active points (paper Fig.
9, as ``stimuli.flow_plan``); a point's pulse focuses on the point against the whole
map (``A = conj(h) h^T``, ``B`` the mean over the grid points + the map error).
"""

from __future__ import annotations

import math
from dataclasses import replace

import numpy as np

from console.plugin_api import (
    OutputPlan,
    Segment,
    UserError,
    VibrationMap,
    check_duration,
    plan_samples,
)
from plugins.vibrotactile.independent import (
    PATCHES,
    choose_bins,
    error_variance,
    generalized_max_batched,
    patch_frf,
    scale_to_peak,
    solve_pairs,
)
from plugins.vibrotactile.interp import interpolate
from plugins.vibrotactile.tables import usable_bins
from plugins.vibrotactile.thresholds import Perception

#: [audio] channels of the paper's bus (the default)
BUS = ("piezo", "screen")


def per_patch_channels(profile) -> bool:
    """True when the profile's ``[audio] channels`` give PA..PD a channel each."""
    names = profile.get("audio.channels", BUS) or BUS
    return all(p in names for p in PATCHES)


def refuse_on_bus(profile, what: str, method: str) -> None:
    """One line when ``method`` needs per-patch channels and the profile has the bus."""
    if method != "paper" and not per_patch_channels(profile):
        names = list(profile.get("audio.channels", BUS) or BUS)
        raise UserError(
            f"{what} method {method!r} drives each patch on its own: this profile's "
            f"[audio] channels are {names}; use method 'paper', or a profile with "
            '[audio] channels = ["PA", "PB", "PC", "PD", "screen"]'
        )


def per_patch_segment(
    freq_hz: float,
    amp_v: float,
    weights: np.ndarray,
    duration_s: float,
    ramp_s: float,
    sample_rate_hz: int,
    label: str = "",
) -> Segment:
    """Sines of one frequency, amplitude ``amp_v |x_p|`` and phase ``arg x_p`` per patch,
    under linear ramps (exactly 0 V at the first and last sample)."""
    n = plan_samples(duration_s, sample_rate_hz, what=label or "tone")
    nr = max(1, int(round(ramp_s * sample_rate_hz)))
    if n < 2 * nr + 1:
        raise UserError(
            f"stimulus of {duration_s:g} s is shorter than its two {ramp_s * 1e3:g} ms ramps"
        )
    env = np.ones(n)
    env[:nr] = np.arange(nr) / nr
    env[-nr:] = np.arange(nr)[::-1] / nr
    u = amp_v * env * np.exp(2j * np.pi * freq_hz * np.arange(n) / sample_rate_hz)
    drives = {p: np.imag(complex(w) * u) for p, w in zip(PATCHES, weights, strict=True)}
    return Segment.per_patch(drives, label=label)


def describe_part(ans: dict, amp: float) -> dict:
    """JSON-able part: the per-patch volts and phases instead of the complex weights."""
    w = np.asarray(ans["weights"], complex)
    out = {k: v for k, v in ans.items() if k != "weights"}
    if isinstance(out.get("levels_um_per_v"), np.ndarray):
        out["levels_um_per_v"] = out["levels_um_per_v"].tolist()
    out["amplitude_v"] = float(amp)
    out["patch_v"] = {p: float(amp * abs(x)) for p, x in zip(PATCHES, w, strict=True)}
    out["patch_phase_deg"] = {
        p: float(np.degrees(np.angle(x))) for p, x in zip(PATCHES, w, strict=True)
    }
    return out


def _with_points(m: VibrationMap, pts: list, method: str) -> tuple[VibrationMap, np.ndarray]:
    """A map of just these points (grid indices, or (x, y) mm interpolated) and the
    error variance of the whole map (the solution's regularisation stays the map's)."""

    xy = np.array([m.points_mm[p] if isinstance(p, int) else p for p in pts], float)
    frf = np.stack(
        [
            m.frf_um_per_v[:, p]
            if isinstance(p, int)
            else interpolate(m, xy[i : i + 1], method)[:, 0]
            for i, p in enumerate(pts)
        ],
        axis=1,
    )
    sub = replace(
        m, frf_um_per_v=frf, points=np.arange(1, len(pts) + 1), points_mm=xy
    )  # fmt: skip
    return sub, error_variance(patch_frf(m), 1.0)


def flow_plan(
    m: VibrationMap,
    a,
    b,
    perception: Perception,
    settings,
    *,
    method: str = "independent",
    cap_v: float,
    band_hz: float,
    map_error_rel: float,
    max_plan_s: float,
    name: str = "",
) -> OutputPlan:
    """Two-part flow from ``a`` to ``b`` (map indices or (x, y) mm) with per-patch drives;
    ``meta``: ``method``, ``parts`` (frequency, per-patch volts and phases, active and
    passive um/V, map and expected contrast), ``predicted_contrast_db`` (the smaller
    expected contrast of the two parts) and ``sensation_level_db``."""
    sub, var = _with_points(m, [a, b], settings.interpolation)
    eps = map_error_rel**2 * var
    parts = solve_pairs(
        sub, [(0, 1), (1, 0)], perception, cap_v=cap_v, band_hz=band_hz, method=method,
        target_sl_db=settings.sensation_level_db, eps=eps,
    )  # fmt: skip
    max_sl = [
        20 * math.log10(max(p["active_um_per_v"] * cap_v, 1e-300)) - p["threshold_db"]
        for p in parts
    ]
    sl = min(settings.sensation_level_db, *max_sl)
    check_duration(
        2 * settings.part_s + settings.gap_s, max_plan_s, f"{name or 'flow'}: parts and gap"
    )
    segs, meta_parts = [], []
    for i, p in enumerate(parts):
        amp = min(10 ** ((p["threshold_db"] + sl) / 20) / max(p["active_um_per_v"], 1e-300), cap_v)
        segs.append(
            per_patch_segment(
                p["frequency_hz"], amp, p["weights"], settings.part_s, settings.ramp_ms / 1e3,
                settings.sample_rate_hz, label=f"part {i + 1} {method}",
            )
        )  # fmt: skip
        meta_parts.append(describe_part(p, amp))
    notes = []
    if sl < 3 * perception.jnd_db:
        notes.append(
            f"sensation level only {sl:.1f} dB (drive limit {cap_v:g} V): may be hard to feel"
        )
    meta = {
        "kind": "flow",
        "method": method,
        "sensation_level_db": float(sl),
        "parts": meta_parts,
        "predicted_contrast_db": float(min(p["expected_contrast_db"] for p in parts)),
        "map_error_rel": float(map_error_rel),
        "notes": notes,
    }
    return OutputPlan(
        settings.sample_rate_hz, tuple(segs), name=name or "flow", gap_s=settings.gap_s, meta=meta
    )


def hand_flow_plan(
    parts: list[dict], center_mm, direction: str, hand_mm: float, settings, method: str,
    name: str = "",
) -> OutputPlan:  # fmt: skip
    """The two parts of ``independent.solve_region`` as a plan (``meta`` as the paper's
    hand flow: ``center_mm``, ``direction``, ``parts``; plus ``method`` and
    ``predicted_contrast_db``, the weaker part's margin on the map)."""
    st = settings
    segs = tuple(
        per_patch_segment(
            p["frequency_hz"], p["amplitude_v"], p["weights"], st.part_s, st.ramp_ms / 1e3,
            st.sample_rate_hz, label=f"part {i + 1} {method}",
        )
        for i, p in enumerate(parts)
    )  # fmt: skip
    cx, cy = (float(c) for c in center_mm)
    meta = {
        "kind": "hand_flow",
        "ok": True,
        "center_mm": [cx, cy],
        "direction": direction,
        "hand_mm": float(hand_mm),
        "method": method,
        "parts": [describe_part(p, p["amplitude_v"]) for p in parts],
        "predicted_contrast_db": float(min(p["contrast_db"] for p in parts)),
    }
    return OutputPlan(
        st.sample_rate_hz,
        segs,
        name=name or f"hand flow {direction} at {cx:g},{cy:g} mm ({method})",
        gap_s=st.gap_s,
        meta=meta,
    )


def solve_focus(
    m: VibrationMap,
    h_a: np.ndarray,
    perception: Perception,
    *,
    cap_v: float,
    target_sl_db: float,
    band_hz: float,
    map_error_rel: float,
    method: str = "independent",
) -> dict:
    """The drive (4,) and bin that make the point strongest against the map's mean
    (``A = conj(h_a) h_a^T``, ``B`` = mean over grid points of ``conj(h) h^T`` + eps);
    ``time_reversal``: ``x = conj(h_a)``."""
    keep = usable_bins(m, band_hz)
    h = patch_frf(m, keep)  # (4, P, K)
    eps = error_variance(h, map_error_rel)
    ha = np.asarray(h_a)[:, keep].T  # (K, 4)
    a = np.einsum("ki,kj->kij", np.conj(ha), ha)
    b = np.einsum("ipk,jpk->kij", np.conj(h), h) / h.shape[1] + eps[:, None, None] * np.eye(4)
    if method == "time_reversal":
        x = np.conj(ha)
        lam = np.abs(np.einsum("kij,ki,kj->k", a, np.conj(x), x)) / np.abs(
            np.einsum("kij,ki,kj->k", b, np.conj(x), x)
        )
    else:
        x, lam = generalized_max_batched(a, b)
    x = scale_to_peak(x, ha)
    ga = np.abs(np.sum(ha * x, axis=-1))
    mean = np.sqrt(np.mean(np.abs(np.einsum("ipk,ki->kp", h, x)) ** 2, axis=1))
    f = m.freq_hz[keep]
    k = int(choose_bins(ga[None], lam[None].real, f, perception, cap_v, target_sl_db)[0])
    thr = float(perception.threshold_db(f[k], "fingertip"))
    amp = min(10 ** ((thr + target_sl_db) / 20) / max(ga[k], 1e-300), cap_v)
    return {
        "frequency_hz": float(f[k]),
        "weights": x[k],
        "um_per_v": float(ga[k]),
        "median_grid_um_per_v": float(np.median(np.abs(np.einsum("ipk,i->p", h[:, :, [k]], x[k])))),
        "contrast_db": float(20 * math.log10(ga[k] / max(mean[k], 1e-300))),
        "amplitude_v": float(amp),
        "threshold_db": thr,
        "sensation_level_db": float(20 * math.log10(max(ga[k] * amp, 1e-300)) - thr),
    }


def point_plan(
    m: VibrationMap,
    a,
    perception: Perception,
    settings,
    *,
    cap_v: float,
    band_hz: float,
    map_error_rel: float,
    max_plan_s: float,
    method: str = "independent",
    name: str = "",
) -> OutputPlan:
    """A pulse focused on ``a`` (map index or (x, y) mm) with per-patch drives;
    ``meta`` as the paper's pulse plus ``method``, ``patch_v``, ``patch_phase_deg`` and
    ``contrast_db`` (the point against the RMS over the grid)."""
    sub, _ = _with_points(m, [a], settings.interpolation)
    idx = [sub.excitations.index(p) for p in PATCHES]
    ans = solve_focus(
        m, sub.frf_um_per_v[idx, 0], perception, cap_v=cap_v, band_hz=band_hz,
        target_sl_db=settings.sensation_level_db, map_error_rel=map_error_rel, method=method,
    )  # fmt: skip
    check_duration(settings.pulse_s, max_plan_s, f"{name or 'point'}: pulse")
    seg = per_patch_segment(
        ans["frequency_hz"], ans["amplitude_v"], ans["weights"], settings.pulse_s,
        min(settings.ramp_ms / 1e3, settings.pulse_s / 4), settings.sample_rate_hz,
        label=f"point {method}",
    )  # fmt: skip
    meta = {"kind": "point", "method": method, **describe_part(ans, ans["amplitude_v"])}
    meta["predicted_contrast_db"] = meta["contrast_db"]
    return OutputPlan(settings.sample_rate_hz, (seg,), name=name or "point", meta=meta)
