"""Stimulus levels per participant for hand flows (exp2) and the knob (``sensation.py``).

``[study] level = "20 dB SL"`` (or ``"1.5 V"``) on a ``hand_flow`` or ``knob`` study is
resolved, like exp1's flows, before ``plan.json`` is written, from the participant's
``thresholds.json``; the trial's ``stimulus["level"]`` records it.

Hand flows (``resolve_hand_plan``): each (region, direction) is rendered at the effect's
own level; every part's drive is set so its strongest active square (the displacement at
least half of the square's points reach, ``H`` um/V) sits ``SL`` above the participant's
``vibrotactile`` curve (``dB re 1 um``: a threshold at the skin) at the part's carrier:
``V = 10^((T + SL) / 20) / H``. The part records ``freq_hz``, ``threshold_db``,
``reference``, ``um_per_v``, ``amplitude_v`` and ``passive_sl_db`` (the passive side's
level above the threshold: ``SL`` minus the part's margin). ``sensation.apply_level``
scales the rendered parts when the trial plays (through the gate as always).

The knob (``resolve_knob_plan``): the electrovibration signals of each condition, from
the participant's ``electrovibration`` curve (``dB re 1 V`` peak at the screen) for the
signal's waveform and frequency: the detent (``HD``) a ``square`` at ``[knob]
detent_freq_hz`` (a single pulse, ``detent_freq_hz = 0``: half a period of
``detent_ms``), the friction a ``sine`` at ``cf_freq_hz`` (``CF``, ``BF``) or over
``vf_freq_at_rest_hz .. vf_freq_at_speed_hz`` (``VF``: set at the frequency of that range
where the threshold is highest, so every frequency of the sweep is at least ``SL``).
Each part records ``signal``, ``waveform``, ``freq_hz``, ``threshold_db``, ``reference``,
``amplitude_v`` (peak), ``vpp`` and ``knob`` (the ``[knob]`` keys it sets); the trial
runs with those keys (``knob_profile``). ``V`` plays nothing; a vibrotactile detent
(``VD``) takes no electrovibration level and is refused.

Refused in one line, never played lower: a participant without the curve (naming the
threshold protocol to run), a curve that does not reach the frequency, a drive above
the safety gate's limits for that signal (``adaptive_levels.max_volts``: the channel's
range, relay rating and slew, as the gate checks them; a hand flow also ``[vibrotactile]
drive_max_v``). A simulated participant without a curve gets one from its observer's
parameters (``threshold_offset_db``): the profile's ``[perception]`` fingertip curve,
or the ``[electrostatic]`` sine and square thresholds (``ev_curves``).
"""

from __future__ import annotations

import dataclasses
import json
import math
from collections.abc import Callable
from typing import Any

import numpy as np

from console.plugin_api import Limits, OutputPlan, UserError

from . import adaptive_levels as al
from . import thresholds as th

#: [electrostatic] population thresholds (Vpp) when a profile lacks them (FACTS.md)
EV_DEFAULT_FREQ_HZ = [15.0, 30.0, 60.0, 80.0, 120.0, 180.0, 240.0, 480.0, 960.0, 1920.0]
EV_DEFAULT_SINE_VPP = [62.0, 44.0, 31.0, 27.0, 29.0, 33.0, 38.0, 55.0, 80.0, 115.0]
EV_DEFAULT_SQUARE_VPP = [38.0, 31.0, 27.0, 26.0, 29.0, 33.0, 38.0, 55.0, 80.0, 115.0]
#: a knob level may sit this far above the gate's largest (float rounding only)
TOLERANCE_REL = 1e-6


def observer_offset_db(observer: dict[str, Any]) -> float:
    off = observer.get("threshold_offset_db", 0.0)
    if isinstance(off, bool) or not isinstance(off, (int, float)) or not math.isfinite(off):
        raise UserError(
            f"participant.json: observer.threshold_offset_db = {off!r}: must be a number of dB"
        )
    return float(off)


def ev_curves(observer: dict[str, Any], electrostatic: dict[str, Any]) -> list[dict[str, Any]]:
    """A simulated participant's electrovibration curves (sine and square, dB re 1 V
    peak): ``[electrostatic]`` thresholds (Vpp) + the observer's ``threshold_offset_db``."""
    off = observer_offset_db(observer)
    freq = [float(f) for f in electrostatic.get("threshold_freq_hz", EV_DEFAULT_FREQ_HZ)]
    out = []
    for waveform, key, default in (
        ("sine", "threshold_vpp", EV_DEFAULT_SINE_VPP),
        ("square", "threshold_square_vpp", EV_DEFAULT_SQUARE_VPP),
    ):
        vpp = [float(v) for v in electrostatic.get(key, default)]
        out.append(
            {
                "modality": "electrovibration",
                "waveform": waveform,
                "point": None,
                "reference": "dB re 1 V",
                "freq_hz": freq,
                "threshold_db": [20 * math.log10(v / 2) + off for v in vpp],
                "ci_db": None,
                "procedure": f"simulated: profile [electrostatic] {key} + observer "
                "threshold_offset_db",
                "protocol_sha256": "",
            }
        )
    return out


def _too_loud(what: str, level: Any, r: dict[str, Any], cap: float, where: str) -> UserError:
    thr = (
        ""
        if r.get("threshold_db") is None
        else f" (threshold {r['threshold_db']:.1f} {r['reference']})"
    )
    return UserError(
        f"{what}: {level.text} at {r['freq_hz']:g} Hz needs {r['amplitude_v']:.1f} V peak{thr}, "
        f"above the drive limit {cap:.1f} V ({where}); give a lower study.level"
    )


# ------------------------------------------------------------------------ hand flows
def hand_um_per_v(meta: dict[str, Any], part: dict[str, Any]) -> float:
    """The part's strongest active square per volt: the independent solve's
    ``levels_um_per_v``, or the paper's search, whose parts sit ``level_above_3jnd_db``
    above the 3-JND line ``x_um`` at that square."""
    if part.get("levels_um_per_v") is not None:
        return float(np.max(np.asarray(part["levels_um_per_v"], float)))
    s = meta.get("level_above_3jnd_db")
    if s is None or not part.get("x_um") or not part.get("amplitude_v"):
        return 0.0
    return float(part["x_um"]) * 10 ** (float(s) / 20) / float(part["amplitude_v"])


def resolve_hand_plan(
    plan: dict[str, Any],
    level: Any,
    curves: list[dict[str, Any]],
    render: Callable[[dict[str, Any]], OutputPlan],
    limits: Limits,
    drive_max_v: float,
) -> dict[str, Any]:
    """``plan`` with each hand-flow trial's ``stimulus["level"]`` (module docstring)."""
    pid = plan.get("participant", "participant")
    curve = None
    if level.kind == "sl":
        curve = th.find_curve(curves, "vibrotactile", "sine", None)
        if curve is None or curve["reference"] != "dB re 1 um":
            raise UserError(
                f"{pid}: a hand flow needs a vibrotactile threshold in dB re 1 um (at the "
                "skin); measure one (threshold_vibrotactile) or give the level in V"
            )
    done: dict[tuple, dict[str, Any]] = {}
    for trial in plan["trials"]:
        s = trial["stimulus"]
        if s.get("effect") != "hand_flow":
            continue
        key = (tuple(float(c) for c in s["center_mm"]), s["direction"])
        if key not in done:
            rendered = render(trial)
            parts = rendered.meta.get("parts") or []
            if len(parts) != len(rendered.segments):
                raise UserError(
                    f"{rendered.name}: the effect's parts do not match its segments; "
                    "give the level in V or another [vibrotactile] method"
                )
            resolved = []
            for i, (part, seg) in enumerate(zip(parts, rendered.segments, strict=True)):
                what = f"{pid}: {rendered.name} part {i + 1}"
                f, h = float(part["frequency_hz"]), hand_um_per_v(rendered.meta, part)
                r: dict[str, Any] = {"freq_hz": f, "um_per_v": h}
                if curve is None:
                    r.update(threshold_db=None, reference=None, amplitude_v=level.value)
                else:
                    if h <= 0:
                        raise UserError(f"{what}: the effect gives no um/V; give the level in V")
                    t = th.interpolate_db(curve, f, f"{what}: vibrotactile threshold curve")
                    volts = 10 ** ((t + level.value) / 20) / h
                    r.update(threshold_db=t, reference=curve["reference"], amplitude_v=volts)
                margin = part.get("margin_db", part.get("min_active_contrast_db"))
                if margin is not None and level.kind == "sl":
                    r["passive_sl_db"] = float(level.value - float(margin))
                gate = float(part["amplitude_v"]) * al.max_volts(limits, seg)
                cap = min(gate, float(drive_max_v))
                if r["amplitude_v"] > cap * (1 + TOLERANCE_REL):
                    raise _too_loud(what, level, r, cap, "[limits], [vibrotactile] drive_max_v")
                resolved.append(r)
            sl = level.value if level.kind == "sl" else None
            done[key] = {"level": level.text, "sl_db": sl, "parts": resolved}
        s["level"] = done[key]
    return plan


# ------------------------------------------------------------------------------ knob
def knob_signals(condition: str, knob: dict[str, Any], where: str) -> list[dict[str, Any]]:
    """The electrovibration signals of a knob condition: ``signal``, ``waveform``,
    ``freqs`` (the frequencies it plays), ``keys`` (the ``[knob]`` amplitudes it sets)."""
    name = condition.strip().upper()
    if name == "V":
        return []
    detent, _, friction = name.partition("+")
    out = []
    if detent == "VD":
        raise UserError(
            f"{where}: condition {condition}: its detent is vibrotactile (piezo), a knob "
            "study.level sets the electrovibration signals only; remove the VD conditions "
            "or the level"
        )
    if detent != "HD":
        raise UserError(f"{where}: condition {condition!r}: not a knob condition with a level")
    f_det = float(knob["detent_freq_hz"]) or 1e3 / (2 * float(knob["detent_ms"]))
    out.append({"signal": "detent", "waveform": "square", "freqs": [f_det], "keys": ["detent_vpp"]})
    if friction in ("CF", "BF"):
        keys = ["carrier_vpp"] if friction == "CF" else ["bf_max_vpp", "bf_min_vpp"]
        out.append(
            {"signal": "friction", "waveform": "sine", "freqs": [float(knob["cf_freq_hz"])],
             "keys": keys}
        )  # fmt: skip
    elif friction == "VF":
        lo, hi = sorted((float(knob["vf_freq_at_rest_hz"]), float(knob["vf_freq_at_speed_hz"])))
        freqs = list(np.geomspace(lo, hi, 17)) if hi > lo else [lo]
        out.append(
            {"signal": "friction", "waveform": "sine", "freqs": [float(f) for f in freqs],
             "keys": ["carrier_vpp"]}
        )  # fmt: skip
    elif friction:
        raise UserError(f"{where}: condition {condition!r}: not a knob condition with a level")
    return out


def _unit_detent(knob: dict[str, Any], fs: int) -> np.ndarray:
    """A unit detent as the knob plays it: ``detent_ms`` long, raised-cosine edges of
    ``detent_edge_ms``; a square burst at ``detent_freq_hz`` (> 0) with those edges."""
    n = max(4, int(round(float(knob["detent_ms"]) * 1e-3 * fs)))
    e = max(1, min(int(round(float(knob["detent_edge_ms"]) * 1e-3 * fs)), n // 2))
    env = np.ones(n)
    env[:e] = 0.5 - 0.5 * np.cos(np.pi * np.arange(e) / e)
    env[n - e :] = env[:e][::-1]
    f = float(knob["detent_freq_hz"])
    if f > 0:
        frac = min(float(knob["detent_edge_ms"]) * 1e-3 * f, 0.25)
        g = 1.0 / math.sin(math.pi * max(frac, 1e-4))
        env = env * np.clip(g * np.sin(2 * np.pi * f * np.arange(n) / fs), -1.0, 1.0)
    return np.concatenate([[0.0], env, [0.0]])


def _gate_cap(limits: Limits, sig: dict[str, Any], knob: dict[str, Any]) -> float:
    """The gate's largest peak for the signal on the screen (the slew at its highest
    frequency, the detent's edges as the knob shapes them)."""
    fs = int(limits.sample_rate_hz)
    if sig["signal"] == "detent":
        unit = _unit_detent(knob, fs)
    else:
        unit = al.unit_wave(max(sig["freqs"]), "sine", 0.2, 0.01, fs)
    return al.max_volts(limits, al.segment(al.Channel("electrovibration"), unit))


def _knob_part(
    sig: dict[str, Any], level: Any, curves: list[dict[str, Any]], knob: dict, limits: Limits,
    what: str,
) -> dict[str, Any]:  # fmt: skip
    r: dict[str, Any] = {"signal": sig["signal"], "waveform": sig["waveform"]}
    if len(sig["freqs"]) > 1:
        r["freq_range_hz"] = [min(sig["freqs"]), max(sig["freqs"])]
    if level.kind == "volts":
        f, t, ref, volts = sig["freqs"][0], None, None, level.value
    else:
        curve = th.find_curve(curves, "electrovibration", sig["waveform"], None)
        if curve is None:
            raise UserError(
                f"{what}: no electrovibration {sig['waveform']} threshold; measure it "
                "(threshold_electrovibration) or give the level in V"
            )
        where = f"{what}: electrovibration {sig['waveform']} threshold curve"
        ts = [th.interpolate_db(curve, f, where) for f in sig["freqs"]]
        k = int(np.argmax(ts))
        f, t, ref = sig["freqs"][k], ts[k], curve["reference"]
        volts = 10 ** ((t + level.value) / 20)
    r.update(freq_hz=float(f), threshold_db=t, reference=ref, amplitude_v=float(volts))
    r["vpp"] = 2 * float(volts)
    cap = _gate_cap(limits, sig, knob)
    if volts > cap * (1 + TOLERANCE_REL):
        raise _too_loud(what, level, r, cap, "the safety gate's [limits] for the screen")
    sets = {sig["keys"][0]: r["vpp"]}
    if len(sig["keys"]) > 1:  # boundary friction: its mid-sector level in proportion
        ratio = float(knob[sig["keys"][1]]) / max(float(knob[sig["keys"][0]]), 1e-12)
        sets[sig["keys"][1]] = r["vpp"] * ratio
    r["knob"] = sets
    return r


def resolve_knob_plan(
    plan: dict[str, Any],
    level: Any,
    curves: list[dict[str, Any]],
    knob: dict[str, Any],
    limits: Limits,
) -> dict[str, Any]:
    """``plan`` with each knob trial's ``stimulus["level"]`` (module docstring);
    ``knob``: the profile's ``[knob]`` section."""
    pid = plan.get("participant", "participant")
    done: dict[str, dict[str, Any]] = {}
    for trial in plan["trials"]:
        s = trial["stimulus"]
        if s.get("task") != "knob":
            continue
        cond = str(s["condition"])
        if cond not in done:
            what = f"{pid}: knob {cond}"
            parts = [
                _knob_part(sig, level, curves, knob, limits, f"{what} {sig['signal']}")
                for sig in knob_signals(cond, knob, what)
            ]
            sl = level.value if level.kind == "sl" else None
            done[cond] = {"level": level.text, "sl_db": sl, "parts": parts}
        s["level"] = done[cond]
    return plan


KNOB_KEYS = ("detent_vpp", "detent_freq_hz", "detent_ms", "carrier_vpp", "cf_freq_hz",
             "vf_freq_at_rest_hz", "vf_freq_at_speed_hz", "bf_max_vpp", "bf_min_vpp")  # fmt: skip


def knob_section(profile: Any) -> dict[str, Any]:
    """The profile's ``[knob]`` (the electrostatic plugin declares it, defaults filled)."""
    knob = dict(profile.section("knob") or {})
    missing = [k for k in KNOB_KEYS if k not in knob]
    if missing:
        raise UserError(
            f"profile {getattr(profile, 'name', '')}: [knob] has no {missing[0]}: a knob "
            "study.level needs the electrostatic plugin (enable it) or give no level"
        )
    return knob


_PROFILES: dict[str, Any] = {}


def knob_profile(profile: Any, level: dict[str, Any]) -> Any:
    """``profile`` with the ``[knob]`` amplitudes of a trial's resolved ``level`` (the
    knob effect reads its signals from there); one object per profile and level."""
    sets: dict[str, float] = {}
    for part in level.get("parts") or []:
        sets.update({k: float(v) for k, v in part.get("knob", {}).items()})
    if not sets:
        return profile
    key = f"{id(profile)}:{json.dumps(sets, sort_keys=True)}"
    hit = _PROFILES.get(key)
    if hit is not None and hit[0] is profile:
        return hit[1]
    if isinstance(profile, dict):
        new = {**profile, "knob": {**profile.get("knob", {}), **sets}}
    else:
        data = {**profile.data, "knob": {**profile.section("knob"), **sets}}
        new = dataclasses.replace(profile, data=data)
    if len(_PROFILES) >= 16:
        _PROFILES.pop(next(iter(_PROFILES)))
    _PROFILES[key] = (profile, new)
    return new


def resolver_for(
    protocol: Any,
    profile: Any,
    render: Callable[[dict[str, Any]], OutputPlan],
    level: Any,
    modality: str,
    participant_curves: Callable[..., list[dict[str, Any]]],
) -> Callable[[dict[str, Any], Any, dict[str, Any]], dict[str, Any]]:
    """``resolve(plan, folder, participant)`` of a hand-flow or knob study (``sensation.
    resolver`` hands these over, with the stimulus's ``modality`` and its
    ``participant_curves``)."""
    limits = Limits.from_profile(profile)
    perception = dict(profile.section("perception") or {})
    make = None
    if modality == "electrovibration":
        electrostatic = dict(profile.section("electrostatic") or {})

        def make(observer: dict[str, Any]) -> list[dict[str, Any]]:
            return ev_curves(observer, electrostatic)

    def resolve(plan: dict[str, Any], folder: Any, participant: dict[str, Any]) -> dict[str, Any]:
        curves = (
            participant_curves(folder, participant, modality, perception, make)
            if level.kind == "sl"
            else []
        )
        if protocol.stimulus == "knob":
            return resolve_knob_plan(plan, level, curves, knob_section(profile), limits)
        drive = float(profile.get("vibrotactile.drive_max_v", math.inf) or math.inf)
        return resolve_hand_plan(plan, level, curves, render, limits, drive)

    return resolve
