"""Apple's AHAP (Apple Haptic and Audio Pattern) files read into and written from the
shared model (``console.signals.haptic_files``: the mapping onto the patches).

An AHAP file is JSON: ``{"Version": 1.0, "Metadata": {...}, "Pattern": [...]}``; each
pattern entry is one of

- ``{"Event": {"Time", "EventType", "EventDuration", "EventParameters": [{"ParameterID",
  "ParameterValue"}]}}``: ``HapticContinuous`` (intensity ``HapticIntensity`` 0..1, carrier
  ``HapticSharpness`` 0..1, shape ``AttackTime``, ``DecayTime``, ``ReleaseTime`` in s and
  ``Sustained`` 0/1), ``HapticTransient`` (a burst), ``AudioCustom`` / ``AudioContinuous``
  (dropped: the table plays no sound);
- ``{"Parameter": {"ParameterID", "Time", "ParameterValue"}}``: a dynamic parameter set at
  ``Time`` (``HapticIntensityControl`` multiplies intensity, ``HapticSharpnessControl``
  adds to sharpness, -1..1), here over an edge of ``EDGE_S``;
- ``{"ParameterCurve": {"ParameterID", "Time", "ParameterCurveControlPoints": [{"Time",
  "ParameterValue"}]}}``: the same, linear between points timed from ``Time``.

Continuous events that overlap add up (clipped at 1). A sustained event holds its
intensity after the attack and falls over the release at its end; one that is not
sustained falls to 0 over the decay after the attack. Export writes one continuous event
under intensity and sharpness curves of at most 16 control points each (what Core
Haptics accepts), chained.
"""

from __future__ import annotations

import json
from pathlib import Path
from typing import Any

import numpy as np

from console.core.plain_numbers import plain_s
from console.signals.haptic_files import (
    EDGE_S,
    MAX_TIME_S,
    Exported,
    Pattern,
    bad,
    load_json,
    make_grid,
    need,
    num,
)

EVENT_TYPES = ("HapticContinuous", "HapticTransient", "AudioCustom", "AudioContinuous")
EVENT_PARAMS = {"HapticIntensity": (0, 1), "HapticSharpness": (0, 1), "AttackTime": (0, 60),
                "DecayTime": (0, 60), "ReleaseTime": (0, 60), "Sustained": (0, 1)}  # fmt: skip
CONTROLS = {"HapticIntensityControl": (0.0, 1.0, 1.0), "HapticSharpnessControl": (-1.0, 1.0, 0.0)}
MAX_CURVE_POINTS = 16
_EXAMPLE = '{"Version": 1.0, "Pattern": [{"Event": {...}}]}'


def read(path: str | Path) -> Pattern:
    """The pattern an AHAP file holds (one ``UserError`` line for anything malformed)."""
    path = Path(path)
    doc = need(path, load_json(path, "AHAP"), dict, "the top level", _EXAMPLE)
    if "Version" in doc:
        v = doc["Version"]
        if isinstance(v, bool) or not isinstance(v, (int, float)) or float(v) != 1.0:
            raise bad(path, "Version", f"{v!r} is not an AHAP version this reader knows",
                      "save the file as AHAP version 1.0")  # fmt: skip
    if "Pattern" not in doc:
        raise bad(path, "Pattern", "missing", f"an AHAP file holds {_EXAMPLE}")
    entries = need(path, doc["Pattern"], list, "Pattern", _EXAMPLE)
    events, controls = [], {k: [] for k in CONTROLS}
    dropped: dict[str, int] = {}
    for i, entry in enumerate(entries):
        where = f"Pattern[{i}]"
        need(path, entry, dict, where, '{"Event": {...}} or {"ParameterCurve": {...}}')
        for kind, body in entry.items():
            at = f"{where}.{kind}"
            if kind == "Event":
                ev = _event(path, need(path, body, dict, at, '{"Time": 0, ...}'), at, dropped)
                if ev is not None:
                    events.append(ev)
            elif kind in ("Parameter", "ParameterCurve"):
                _control(path, need(path, body, dict, at, '{"ParameterID": ...}'), kind, at,
                         controls, dropped)  # fmt: skip
            else:
                dropped[f"pattern entry {kind}"] = dropped.get(f"pattern entry {kind}", 0) + 1
    return _pattern(path, events, controls, dropped)


def _event(path: Path, ev: dict, at: str, dropped: dict) -> dict | None:
    t = num(path, ev, "Time", at, 0.0, MAX_TIME_S)
    kind = ev.get("EventType")
    if kind not in EVENT_TYPES:
        raise bad(path, f"{at}.EventType", f"{kind!r} is not an event type",
                  f"use one of {', '.join(EVENT_TYPES)}")  # fmt: skip
    if kind.startswith("Audio"):
        dropped[f"{kind} event"] = dropped.get(f"{kind} event", 0) + 1
        return None
    params = {"HapticIntensity": 1.0, "HapticSharpness": 0.5, "AttackTime": 0.0,
              "DecayTime": 0.0, "ReleaseTime": 0.0, "Sustained": 1.0}  # fmt: skip
    plist = need(path, ev.get("EventParameters", []), list, f"{at}.EventParameters",
                 '[{"ParameterID": "HapticIntensity", "ParameterValue": 0.8}]')  # fmt: skip
    for j, p in enumerate(plist):
        pw = f"{at}.EventParameters[{j}]"
        need(path, p, dict, pw, '{"ParameterID": "HapticIntensity", "ParameterValue": 0.8}')
        pid = p.get("ParameterID")
        pid = "Sustained" if pid == "Sustain" else pid
        if pid not in EVENT_PARAMS:
            dropped[f"parameter {pid}"] = dropped.get(f"parameter {pid}", 0) + 1
            continue
        params[pid] = num(path, p, "ParameterValue", f"{pw}({pid})", *EVENT_PARAMS[pid])
    dur = 0.0
    if kind == "HapticContinuous":
        dur = num(path, ev, "EventDuration", at, 1e-4, MAX_TIME_S)
    return {"t": t, "kind": kind, "dur": dur, **params}


def _control(path: Path, c: dict, kind: str, at: str, controls: dict, dropped: dict) -> None:
    pid = c.get("ParameterID")
    if pid not in CONTROLS:
        dropped[f"control {pid}"] = dropped.get(f"control {pid}", 0) + 1
        return
    lo, hi, _default = CONTROLS[pid]
    t = num(path, c, "Time", at, 0.0, MAX_TIME_S)
    if kind == "Parameter":
        controls[pid].append((t, [(0.0, num(path, c, "ParameterValue", at, lo, hi))], True))
        return
    pts = need(path, c.get("ParameterCurveControlPoints"), list,
               f"{at}.ParameterCurveControlPoints", '[{"Time": 0, "ParameterValue": 1}]')  # fmt: skip
    if not pts:
        raise bad(path, f"{at}.ParameterCurveControlPoints", "empty", "give at least one point")
    out, last = [], -1.0
    for j, cp in enumerate(pts):
        w = f"{at}.ParameterCurveControlPoints[{j}]"
        need(path, cp, dict, w, '{"Time": 0.1, "ParameterValue": 0.5}')
        tj = num(path, cp, "Time", w, 0.0, MAX_TIME_S)
        if tj < last:
            raise bad(path, f"{w}.Time", f"{plain_s(tj)} comes before the point above",
                      "give control points in time order")  # fmt: skip
        out.append((tj, num(path, cp, "ParameterValue", w, lo, hi)))
        last = tj
    controls[pid].append((t, out, False))


def _control_curve(grid: np.ndarray, items: list, default: float) -> np.ndarray:
    """A control's value on ``grid``: set values reached over ``EDGE_S``, curves linear."""
    pts: list[tuple[float, float]] = [(0.0, default)]

    def push(t: float, v: float) -> None:
        while len(pts) > 1 and pts[-1][0] >= t - 1e-9:
            pts.pop()
        if pts[-1][0] >= t - 1e-9:
            t = pts[-1][0] + 1e-6
        pts.append((t, v))

    for t0, points, is_set in sorted(items, key=lambda x: x[0]):
        first_t, first_v = points[0]
        hold = pts[-1][1]
        push(t0 + first_t, hold)
        if abs(first_v - hold) > 1e-12:
            push(t0 + first_t + (EDGE_S if is_set else 1e-6), first_v)
        for tj, vj in points[1:]:
            push(t0 + tj, vj)
    ts, vs = zip(*pts, strict=True)
    return np.interp(grid, ts, vs)


def _shape(ev: dict, grid: np.ndarray) -> np.ndarray:
    """A continuous event's intensity on ``grid`` (0 outside it)."""
    t0, d = ev["t"], ev["dur"]
    edge = min(EDGE_S, d / 2)
    att = min(max(ev["AttackTime"], edge), d / 2)
    rel = min(max(ev["ReleaseTime"], edge), d - att)
    if ev["Sustained"] >= 0.5:
        ts = [t0, t0 + att, t0 + d - rel, t0 + d]
        vs = [0.0, 1.0, 1.0, 0.0]
    else:
        fall = min(max(ev["DecayTime"], edge), d - att)
        ts, vs = [t0, t0 + att, t0 + att + fall], [0.0, 1.0, 0.0]
    ts = np.maximum.accumulate(np.array(ts) + np.arange(len(ts)) * 1e-9)
    return ev["HapticIntensity"] * np.interp(grid, ts, vs, left=0.0, right=0.0)


def _pattern(path: Path, events: list, controls: dict, dropped: dict) -> Pattern:
    cont = [e for e in events if e["kind"] == "HapticContinuous"]
    trans = [e for e in events if e["kind"] == "HapticTransient"]
    keys = [e["t"] for e in events] + [e["t"] + e["dur"] for e in cont]
    for items in controls.values():
        keys += [t0 + tj for t0, pts, _s in items for tj, _v in pts]
    end = max([e["t"] + e["dur"] for e in cont] + [e["t"] + 0.03 for e in trans] + [0.0])
    if end <= 0:
        raise bad(path, "Pattern", "no haptic event", "add a HapticContinuous or "
                  "HapticTransient event")  # fmt: skip
    grid = make_grid(end, keys + [k + EDGE_S for k in keys])
    gain = _control_curve(grid, controls["HapticIntensityControl"], 1.0)
    shift = _control_curve(grid, controls["HapticSharpnessControl"], 0.0)
    amp, sharp, best = np.zeros(grid.size), np.full(grid.size, np.nan), np.zeros(grid.size)
    for ev in cont:
        a = _shape(ev, grid)
        amp += a
        louder = a > best
        sharp[louder], best[louder] = ev["HapticSharpness"], a[louder]
    if np.all(np.isnan(sharp)):
        sharp[:] = 0.5
    sharp = _fill(sharp)
    clipped = bool(np.any(amp > 1 + 1e-9))
    amp = np.clip(amp, 0.0, 1.0) * gain
    sharp = np.clip(sharp + shift, 0.0, 1.0)
    transients = []
    for e in trans:
        g = float(np.interp(e["t"], grid, gain))
        s = float(np.clip(e["HapticSharpness"] + np.interp(e["t"], grid, shift), 0, 1))
        transients.append((e["t"], e["HapticIntensity"] * g, s))
    mapped = [f"{len(cont)} continuous events", f"{len(trans)} transients"]
    mapped += [f"{len(v)} {k}" for k, v in controls.items() if v]
    drop = [f"{n} {k}" if n > 1 else k for k, n in dropped.items()]
    if clipped:
        drop.append("intensity above 1 where events overlap (clipped)")
    return Pattern("AHAP", path, grid, amp, sharp, transients, mapped, drop)


def _fill(x: np.ndarray) -> np.ndarray:
    """NaN gaps filled with the nearest value before (or after, at the start)."""
    ok = np.flatnonzero(~np.isnan(x))
    idx = np.searchsorted(ok, np.arange(x.size), side="right") - 1
    return x[ok[np.maximum(idx, 0)]]


def _curves(pid: str, t: np.ndarray, v: np.ndarray) -> list[dict]:
    """``ParameterCurve`` entries of at most 16 points each, each starting where the one
    before ended."""
    out, i = [], 0
    while i < t.size - 1 or (i == 0 and t.size == 1):
        j = min(i + MAX_CURVE_POINTS, t.size)
        t0 = float(t[i])
        pts = [{"Time": round(float(tk) - t0, 6), "ParameterValue": round(float(vk), 5)}
               for tk, vk in zip(t[i:j], v[i:j], strict=True)]  # fmt: skip
        out.append({"ParameterCurve": {"ParameterID": pid, "Time": round(t0, 6),
                                       "ParameterCurveControlPoints": pts}})  # fmt: skip
        i = j - 1
        if j == t.size:
            break
    return out


def write(e: Exported, description: str) -> str:
    """An AHAP file's text for the exported signal ``e``."""
    base = float(e.sharp[0])
    event = {"Event": {"Time": 0.0, "EventType": "HapticContinuous",
                       "EventDuration": round(e.duration_s, 6), "EventParameters": [
                           {"ParameterID": "HapticIntensity", "ParameterValue": 1.0},
                           {"ParameterID": "HapticSharpness", "ParameterValue": round(base, 5)},
                       ]}}  # fmt: skip
    pattern: list[Any] = [event, *_curves("HapticIntensityControl", e.amp_t_s, e.amp)]
    if np.ptp(e.sharp) > 1e-6:
        pattern += _curves("HapticSharpnessControl", e.sharp_t_s, e.sharp - base)
    doc = {"Version": 1.0, "Metadata": {"Project": "HapTable", "Description": description},
           "Pattern": pattern}  # fmt: skip
    return json.dumps(doc, indent=1) + "\n"
