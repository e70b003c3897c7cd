"""Stimulus levels per participant: a protocol's ``level = "20 dB SL"`` (or ``"1.5 V"``).

``[study] level`` (``parse_level``): ``"<n> dB SL"``, a sensation level above the
participant's own detection threshold, or ``"<v> V"``, a peak drive in volts for every
part; empty: the effect's own level (the profile's population curve). Flow studies
(exp1), hand flows (exp2) and the knob take it.

At plan time (``start.prepare``, given ``resolver(...)``) each flow of the plan is
rendered at the effect's level and every part's drive resolved from the participant's
``thresholds.json`` (``thresholds.threshold_at``) at the part's carrier frequency and
active grid point:

- curve in ``dB re 1 um``: ``V = 10^((T + SL) / 20) / H``, ``H`` the active point's
  um/V at the carrier (the effect's ``active_um_per_v``);
- curve in ``dB re 1 V``: ``V = 10^((T + SL) / 20)``.

A drive above the effect's drive limit (inside the safety gate's limits) is refused in
one line, never played lower; so is a participant without a vibrotactile curve. The plan
records it in the trial's ``stimulus["level"]``: ``level`` (the text), ``sl_db`` and per
part ``freq_hz``, ``threshold_db``, ``reference``, ``um_per_v``, ``amplitude_v``;
``apply_level`` scales the rendered parts to those volts when the trial is played.

Hand flows (exp2) and the knob take it too (``sensation_stimuli.py``: a hand flow's
strongest active square at its carrier, the knob's electrovibration signals at their
waveform and frequency, with the same refusals).

A simulated participant without a curve gets one from its observer's parameters
(``simulated_curve``: the profile's ``[perception]`` fingertip curve plus the observer's
``threshold_offset_db``), saved in its folder like a measured one.
"""

from __future__ import annotations

import dataclasses
import math
import re
from collections.abc import Callable
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np

from console.plugin_api import OutputPlan, UserError

from . import thresholds as th

_LEVEL = re.compile(r"^\s*([+-]?\d+(?:\.\d+)?)\s*(dB\s*SL|V)\s*$", re.IGNORECASE)
#: the stimuli whose level the plan resolves, and the modality of their thresholds
MODALITY = {"flow": "vibrotactile", "hand_flow": "vibrotactile", "knob": "electrovibration"}
MAX_SL_DB = 60.0
#: how far the played drive may be from the resolved one before it is refused
TOLERANCE_REL = 1e-6


@dataclass(frozen=True)
class Level:
    """A parsed ``level``: ``kind`` ``sl`` (``value`` dB SL) or ``volts`` (``value`` V)."""

    kind: str
    value: float
    text: str


def parse_level(text: str, where: str = "protocol", stimulus: str = "flow") -> Level | None:
    """``text`` as a ``Level`` (None when empty); one line naming the key otherwise."""
    if not text:
        return None
    m = _LEVEL.match(text)
    if not m:
        raise UserError(
            f'{where}: study.level = {text!r}: give a sensation level ("20 dB SL") or a peak '
            'drive in volts ("1.5 V")'
        )
    value, unit = float(m.group(1)), m.group(2).upper().replace(" ", "")
    if stimulus not in MODALITY:
        raise UserError(
            f"{where}: study.level = {text!r}: only flow, hand_flow and knob studies take a "
            "level; remove it"
        )
    if unit == "V" and not 0 < value <= 1000:
        raise UserError(f"{where}: study.level = {text!r}: give volts above 0 (at most 1000)")
    if unit == "DBSL" and not -20 <= value <= MAX_SL_DB:
        raise UserError(f"{where}: study.level = {text!r}: give -20 .. {MAX_SL_DB:g} dB SL")
    return Level("volts" if unit == "V" else "sl", value, text.strip())


def simulated_curve(observer: dict[str, Any], perception: dict[str, Any]) -> dict[str, Any]:
    """A simulated participant's vibrotactile threshold curve (dB re 1 um peak, fingertip):
    ``[perception]``'s curve + ``fingertip_offset_db`` + the observer's
    ``threshold_offset_db`` (0 when its parameters have none)."""
    off = observer.get("threshold_offset_db", 0.0)
    if isinstance(off, bool) or not isinstance(off, (int, float)) or not math.isfinite(off):
        raise UserError(
            f"participant.json: observer.threshold_offset_db = {off!r}: must be a number of dB"
        )
    tip = float(perception.get("fingertip_offset_db", 6.0))
    freq = [float(f) for f in perception["freq_hz"]]
    thr = [float(t) + tip + float(off) for t in perception["threshold_db_re_1um"]]
    return {
        "modality": "vibrotactile",
        "waveform": "sine",
        "point": None,
        "reference": "dB re 1 um",
        "freq_hz": freq,
        "threshold_db": thr,
        "ci_db": None,
        "procedure": "simulated: profile [perception] fingertip + observer threshold_offset_db",
        "protocol_sha256": "",
    }


def participant_curves(
    folder: Path,
    participant: dict[str, Any],
    modality: str,
    perception: dict[str, Any],
    make: Callable[[dict[str, Any]], list[dict[str, Any]]] | None = None,
) -> list[dict[str, Any]]:
    """The participant's curves; a simulated participant without a ``modality`` curve
    gets ``simulated_curve`` (or ``make(observer)``'s curves) saved first; a person
    without one is one line."""
    curves = th.load_curves(folder)
    if any(c["modality"] == modality for c in curves):
        return curves
    pid = participant.get("id", folder.name)
    if participant.get("simulated"):
        obs = participant.get("observer") or {}
        for c in make(obs) if make is not None else [simulated_curve(obs, perception)]:
            th.save_curve(folder, c)
        return th.load_curves(folder)
    raise UserError(
        f"{pid} has no {modality} threshold ({th.curve_path(folder)}): run `haptable study run "
        f"threshold_{modality} --participant {pid} --out {folder.parent}` first"
    )


def _part_level(
    level: Level, part: dict[str, Any], curves: list[dict[str, Any]], point: Any, what: str
) -> dict[str, Any]:
    f = float(part["frequency_hz"])
    h = float(part.get("active_um_per_v") or part.get("um_per_v") or 0.0)
    out: dict[str, Any] = {"freq_hz": f, "um_per_v": h}
    if level.kind == "volts":
        out.update(threshold_db=None, reference=None, amplitude_v=level.value)
        return out
    curve = th.find_curve(curves, "vibrotactile", "sine", None if point is None else str(point))
    if curve is None:
        raise UserError(
            f"{what}: no vibrotactile threshold in dB re 1 um or at point {point}; measure "
            "one (threshold_vibrotactile) or give the level in V"
        )
    t = th.interpolate_db(curve, f, f"{what}: vibrotactile threshold curve")
    db = t + level.value
    if curve["reference"] == "dB re 1 um":
        if h <= 0:
            raise UserError(f"{what}: the effect gives no um/V at {f:g} Hz; give the level in V")
        volts = 10 ** (db / 20) / h
    else:
        volts = 10 ** (db / 20)
    out.update(threshold_db=t, reference=curve["reference"], amplitude_v=float(volts))
    return out


def drive_cap_v(part: dict[str, Any]) -> float:
    """The effect's drive limit of a part (its level where ``max_sl_db`` puts it)."""
    h = float(part["active_um_per_v"])
    return 10 ** ((float(part["threshold_db"]) + float(part["max_sl_db"])) / 20) / h


def resolve_plan(
    plan: dict[str, Any],
    level: Level,
    curves: list[dict[str, Any]],
    render: Callable[[dict[str, Any]], OutputPlan],
) -> dict[str, Any]:
    """``plan`` with each flow trial's ``stimulus["level"]`` resolved (module docstring);
    ``render(trial)`` is the trial's plan at the effect's own level."""
    pid = plan.get("participant", "participant")
    done: dict[tuple, dict[str, Any]] = {}
    for trial in plan["trials"]:
        s = trial["stimulus"]
        if s.get("effect") != "flow":
            continue
        key = (s["from_point"], s["to_point"])
        if key not in done:
            rendered = render(trial)
            parts = rendered.meta.get("parts") or []
            if len(parts) != len(rendered.segments):
                raise UserError(
                    f"{rendered.name}: the effect's parts do not match its segments (method "
                    f'{rendered.meta.get("method")!r}); use [vibrotactile] method = "paper"'
                )
            resolved = []
            for i, (part, point) in enumerate(zip(parts, key, strict=True)):
                what = f"{pid}: {rendered.name} part {i + 1}"
                r = _part_level(level, part, curves, point, what)
                cap = drive_cap_v(part)
                if r["amplitude_v"] > cap * (1 + TOLERANCE_REL):
                    thr = (
                        ""
                        if r["threshold_db"] is None
                        else f" (threshold {r['threshold_db']:.1f} {r['reference']})"
                    )
                    raise UserError(
                        f"{what}: {level.text} at {r['freq_hz']:g} Hz needs "
                        f"{r['amplitude_v']:.1f} V{thr}, above the drive limit {cap:.1f} V; "
                        "give a lower study.level"
                    )
                resolved.append(r)
            done[key] = {"level": level.text, "sl_db": level.value if level.kind == "sl" else None}
            done[key]["parts"] = resolved
        s["level"] = done[key]
    return plan


def apply_level(rendered: OutputPlan, level: dict[str, Any]) -> OutputPlan:
    """``rendered`` with each part's segment scaled to the plan's resolved volts."""
    parts = rendered.meta.get("parts") or []
    want = level["parts"]
    if len(want) != len(rendered.segments) or len(parts) != len(want):
        raise UserError(f"{rendered.name}: the plan's level has {len(want)} parts; remake it")
    segs, meta_parts = [], []
    for seg, part, w in zip(rendered.segments, parts, want, strict=True):
        k = float(w["amplitude_v"]) / float(part["amplitude_v"])
        segs.append(
            dataclasses.replace(
                seg,
                piezo_v=np.asarray(seg.piezo_v) * k,
                patch_v={p: np.asarray(v) * k for p, v in seg.patch_v.items()},
            )
        )
        meta_parts.append({**part, "amplitude_v": float(w["amplitude_v"]), "level": w})
    meta = {**rendered.meta, "parts": meta_parts, "study_level": level["level"]}
    return dataclasses.replace(rendered, segments=tuple(segs), meta=meta)


def resolver(
    protocol: Any, profile: Any, render: Callable[[dict[str, Any]], OutputPlan]
) -> Callable[[dict[str, Any], Path, dict[str, Any]], dict[str, Any]] | None:
    """``resolve(plan, folder, participant)`` for ``start.prepare`` when the protocol has
    a ``level`` (else None); ``render(trial)``: the trial's plan at the effect's own level
    (``stimuli.EffectPlayer.render_base``)."""
    level = parse_level(protocol.level, protocol.path, protocol.stimulus)
    if level is None:
        return None
    if protocol.stimulus != "flow":  # hand flows and the knob
        # lazy: loaded when this runs, not when the module is imported
        from .sensation_stimuli import resolver_for

        modality = MODALITY[protocol.stimulus]
        return resolver_for(protocol, profile, render, level, modality, participant_curves)
    perception = dict(profile.section("perception") or {})

    def resolve(plan: dict[str, Any], folder: Path, participant: dict[str, Any]) -> dict[str, Any]:
        curves = (
            participant_curves(folder, participant, MODALITY[protocol.stimulus], perception)
            if level.kind == "sl"
            else []
        )
        return resolve_plan(plan, level, curves, render)

    return resolve
