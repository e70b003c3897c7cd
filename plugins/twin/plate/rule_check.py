"""The two lookup-table rules (``perceptual``, ``paper``) compared on the plate twin.

A table entry (excitation, frequency) is chosen from a MEASURED map; what the finger gets
is the TRUE plate's response to the flow that entry makes. Per ordered pair (a, b) the
flow (``stimuli.flow_plan``) drives part 1 (a -> b) and part 2 (b -> a) at amplitudes that
put both active points at the common level ``sl = min(target, each part's reach)`` on the
map: ``V = 10^((T(f) + sl) / 20) / |H_map(a)|``, capped by the drive limit. Steady state on
the twin (its FRF at the grid points, ``Twin.frf_um_per_v``): achieved active and passive
sensation levels ``20 log10(V |H_twin|) - T(f)`` (fingertip threshold of ``[perception]``),
contrast = their difference, felt difference = active SL - max(0, passive SL) in dB and in
JND (``20 log10(1 + w(f))``, the profile's Weber curve). That is cheap for all 84 x 83
pairs; the time response through the safety gate (``loop_check.flow_pairs_check``:
ramps, ring-down, relays) is played for a documented sample.

``accelerance_map``: the twin's map as a lab measures it in acceleration, with noise,
converted back to displacement (``-A / omega^2``): the low-frequency blow-up of issue #14.
"""

from __future__ import annotations

import math
from typing import TYPE_CHECKING

import numpy as np

from console.plugin_api import Limits, VibrationMap, make_map

from .closed_loop import twin_of
from .loop_check import flow_pairs_check
from .loop_play import effects_of
from .loop_report import pair_problems

if TYPE_CHECKING:
    from console.plugin_api import Plugins

#: Accelerance noise: complex Gaussian at 1 % (-40 dB) of the map's median accelerance
#: above 50 Hz, per excitation (an assumption for a swept-sine LDV measurement with few
#: averages, not a measured value); bins below ``[vibrotactile] mask_below_hz`` masked.
ACC_NOISE_REL = 1e-2


def accelerance_map(
    m: VibrationMap, rel: float = ACC_NOISE_REL, seed: int = 1, mask_below_hz: float = 5.0
) -> VibrationMap:
    """``m`` measured as accelerance (m/s^2 per V) with noise ``rel`` x the median
    accelerance above 50 Hz, converted back to displacement by ``-A / omega^2`` (as the
    UFF import does), bins below ``mask_below_hz`` masked."""
    w = 2 * np.pi * m.freq_hz
    acc = -(w**2) * m.frf_um_per_v * 1e-6
    level = np.median(np.abs(acc[:, :, m.freq_hz > 50]), axis=(1, 2))[:, None, None]
    rng = np.random.default_rng(seed)
    noise = rel * level * (rng.standard_normal(acc.shape) + 1j * rng.standard_normal(acc.shape))
    w_safe = np.where(w > 0, w, 1.0)
    disp = np.where(w > 0, -(acc + noise / math.sqrt(2)) / w_safe**2, 0) * 1e6
    return make_map(
        disp,
        m.freq_hz,
        m.points,
        m.points_mm,
        m.excitations,
        m.freq_hz < mask_below_hz,
        source=f"accelerance of {m.provenance.get('source', 'a map')} (noise {rel:g})",
        require_all=False,
    )


def _perception(profile) -> dict:
    return profile.section("perception")


def threshold_db(profile, freq_hz) -> np.ndarray:
    """Fingertip threshold (dB re 1 um) from the ``[perception]`` data."""
    p = _perception(profile)
    f = np.clip(np.asarray(freq_hz, float), 1e-3, None)
    db = np.interp(np.log(f), np.log(p["freq_hz"]), p["threshold_db_re_1um"])
    return db + float(p["fingertip_offset_db"])


def jnd_db(profile, freq_hz) -> np.ndarray:
    """Intensity JND (dB) from the ``[perception]`` Weber curve."""
    p = _perception(profile)
    f = np.clip(np.asarray(freq_hz, float), 1e-3, None)
    wf = p.get("weber_freq_hz", [10.0, 125.0])
    w = np.interp(np.log(f), np.log(wf), p.get("weber_fraction", [0.6, 0.2]))
    return 20 * np.log10(1 + w)


def drive_cap_v(profile) -> float:

    lo, hi = Limits.from_profile(profile).piezo_range()
    return float(min(float(profile.get("vibrotactile.drive_max_v")), -float(lo), float(hi)))


def steady_levels(profile, twin, t, pairs: np.ndarray | None = None) -> dict:
    """Per ordered pair (index pairs (N, 2) into the map, default all) and part 1 (a -> b):
    frequency, actuator, map contrast and the twin's achieved levels (module docstring)."""
    m = t.vmap
    p = m.points.size
    if pairs is None:
        ai, bi = np.nonzero(~np.eye(p, dtype=bool))
    else:
        ai, bi = np.asarray(pairs).T
    f1, f2 = t.freq_hz[ai, bi], t.freq_hz[bi, ai]
    e1, e2 = t.actuator[ai, bi].astype(int), t.actuator[bi, ai].astype(int)
    k1, k2 = np.searchsorted(m.freq_hz, f1), np.searchsorted(m.freq_hz, f2)
    amap = np.abs(m.frf_um_per_v)
    target = float(profile.get("vibrotactile.sensation_level_db"))
    cap = drive_cap_v(profile)
    thr1, thr2 = threshold_db(profile, f1), threshold_db(profile, f2)
    ha1, ha2 = amap[e1, ai, k1], amap[e2, bi, k2]  # map |H| at each part's active point
    reach1 = 20 * np.log10(np.maximum(ha1 * cap, 1e-30)) - thr1
    reach2 = 20 * np.log10(np.maximum(ha2 * cap, 1e-30)) - thr2
    sl = np.minimum(target, np.minimum(reach1, reach2))
    v1 = np.minimum(10 ** ((thr1 + sl) / 20) / np.maximum(ha1, 1e-30), cap)
    # the twin's true FRF at the grid points and the chosen frequencies
    uf, inv = np.unique(f1, return_inverse=True)
    h = np.abs(twin.frf_um_per_v(m.points_mm[:, 0], m.points_mm[:, 1], uf, m.excitations))
    ta, tb = h[e1, ai, inv], h[e1, bi, inv]
    act = 20 * np.log10(np.maximum(v1 * ta, 1e-30)) - thr1
    pas = 20 * np.log10(np.maximum(v1 * tb, 1e-30)) - thr1
    felt = act - np.maximum(pas, 0.0)
    return {
        "a": ai,
        "b": bi,
        "frequency_hz": f1,
        "map_contrast_db": 20
        * np.log10(np.maximum(ha1, 1e-30) / np.maximum(amap[e1, bi, k1], 1e-30)),
        "active_sl_db": act,
        "passive_sl_db": pas,
        "contrast_db": act - pas,
        "felt_db": felt,
        "felt_jnd": felt / jnd_db(profile, f1),
    }


def summary(lv: dict) -> dict:
    """Medians and tails of ``steady_levels`` over its pairs."""
    c, f = lv["contrast_db"], lv["frequency_hz"]
    return {
        "pairs": int(c.size),
        "contrast_db_median": float(np.median(c)),
        "contrast_db_p10": float(np.percentile(c, 10)),
        "contrast_below_3db_pct": float(100 * np.mean(c < 3)),
        "active_sl_db_median": float(np.median(lv["active_sl_db"])),
        "passive_sl_db_median": float(np.median(lv["passive_sl_db"])),
        "passive_felt_pct": float(100 * np.mean(lv["passive_sl_db"] > 0)),
        "felt_jnd_median": float(np.median(lv["felt_jnd"])),
        "freq_hz_median": float(np.median(f)),
        "below_20hz_pct": float(100 * np.mean(f < 20)),
    }


def region_pairs(m: VibrationMap, regions, hand_mm: float = 120.0) -> np.ndarray:
    """Ordered index pairs of the grid points under each hand region (a ``hand_mm``
    square centred there), all regions together."""
    out = []
    for cx, cy in regions:
        d = np.abs(m.points_mm - np.array([cx, cy]))
        inside = np.flatnonzero((d[:, 0] <= hand_mm / 2) & (d[:, 1] <= hand_mm / 2))
        out += [(a, b) for a in inside for b in inside if a != b]
    return np.array(out, dtype=int).reshape(-1, 2)


def compare_rules(
    outputs,
    profile,
    vmap: VibrationMap,
    *,
    plugins: Plugins,
    played_pairs=(),
    regions=(),
    acc_map: VibrationMap | None = None,
) -> dict:
    """Both rules on ``vmap``: steady state on the twin for all pairs and for the pairs
    under ``regions``, ``played_pairs`` (grid numbers) played through the gate; on
    ``acc_map`` (default ``accelerance_map(vmap)``) the frequency each rule picks for
    51 -> 52 and the steady-state levels of all its pairs on the twin."""
    twin = twin_of(profile)
    flow, _ = effects_of(profile, plugins)
    acc = accelerance_map(vmap) if acc_map is None else acc_map
    rp = region_pairs(vmap, regions, float(profile.get("vibrotactile.hand_mm")))
    out: dict = {"noise_rel": ACC_NOISE_REL, "region_pairs": int(len(rp))}
    a51, b52 = vmap.point_index(51), vmap.point_index(52)
    for rule in ("paper", "perceptual"):
        t = flow.tables(vmap=vmap, rule=rule)
        r: dict = {"all_pairs": summary(steady_levels(profile, twin, t))}
        if len(rp):
            r["under_hand"] = summary(steady_levels(profile, twin, t, rp))
        if played_pairs:
            rows = flow_pairs_check(outputs, profile, t, played_pairs, plugins=plugins)
            r["played"] = {
                "pairs": [f"{a}->{b}" for a, b in played_pairs],
                "contrast_db_median": float(np.median([x["ach_contrast_db"] for x in rows])),
                "active_sl_db_median": float(np.median([x["ach_active_sl_db"] for x in rows])),
                "passive_sl_db_median": float(np.median([x["ach_passive_sl_db"] for x in rows])),
                **pair_problems(rows),
                "rows": rows,
            }
        ta = flow.tables(vmap=acc, rule=rule)
        lv = steady_levels(profile, twin, ta)
        r["accelerance"] = {
            "51->52_hz": float(ta.freq_hz[a51, b52]),
            "51->52_actuator": ta.excitations[int(ta.actuator[a51, b52])],
            "52->51_hz": float(ta.freq_hz[b52, a51]),
            **summary(lv),
        }
        out[rule] = r
    return out


def without_rows(res: dict) -> dict:
    """``compare_rules``' result without the played rows (for a compact report)."""
    out = {}
    for k, r in res.items():
        if isinstance(r, dict) and "played" in r:
            r = {**r, "played": {n: v for n, v in r["played"].items() if n != "rows"}}
        out[k] = r
    return out


def format_rules(res: dict) -> str:
    """One line per (rule, set): achieved contrast and levels."""
    head = (
        f"{'rule':>10} {'set':>16} {'pairs':>6} {'C med dB':>8} {'C p10':>6} {'C<3dB %':>7} "
        f"{'A SL':>5} {'P SL':>5} {'P felt %':>8} {'felt JND':>8} {'f med Hz':>8} {'<20Hz %':>7}"
    )
    lines = [head, "(C: achieved active/passive contrast; for 'played' rows p10 is the minimum)"]
    for rule in ("paper", "perceptual"):
        for name in ("all_pairs", "under_hand", "accelerance"):
            s = res[rule].get(name)
            if not s:
                continue
            lines.append(
                f"{rule:>10} {name:>16} {s['pairs']:>6} {s['contrast_db_median']:8.1f} "
                f"{s['contrast_db_p10']:6.1f} {s['contrast_below_3db_pct']:7.1f} "
                f"{s['active_sl_db_median']:5.1f} {s['passive_sl_db_median']:5.1f} "
                f"{s['passive_felt_pct']:8.1f} {s['felt_jnd_median']:8.1f} "
                f"{s['freq_hz_median']:8.1f} {s['below_20hz_pct']:7.1f}"
            )
        pl = res[rule].get("played")
        if pl:
            lines.append(
                f"{rule:>10} {'played (gate)':>16} {len(pl['rows']):>6} "
                f"{pl['contrast_db_median']:8.1f} {pl['min_contrast_db']:6.1f} "
                f"{100 * len(pl['low_contrast']) / len(pl['rows']):7.1f} "
                f"{pl['active_sl_db_median']:5.1f} {pl['passive_sl_db_median']:5.1f}"
            )
    for rule in ("paper", "perceptual"):
        a = res[rule]["accelerance"]
        lines.append(
            f"accelerance map ({res['noise_rel']:g} noise), {rule}: 51->52 at "
            f"{a['51->52_hz']:g} Hz ({a['51->52_actuator']}), 52->51 at {a['52->51_hz']:g} Hz"
        )
    return "\n".join(lines)
