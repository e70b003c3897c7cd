"""A participant's threshold curves: ``DIR/<participant>/thresholds.json``.

The file is ``{"participant": id, "curves": [curve, ...]}``; each curve is one measured
detection-threshold-vs-frequency curve:

| key | value |
|---|---|
| ``modality`` | ``vibrotactile`` or ``electrovibration`` |
| ``waveform`` | ``sine``, ``square`` or null |
| ``point`` | the grid point id it was measured at, or null |
| ``reference`` | ``dB re 1 V`` (drive voltage, peak) or ``dB re 1 um`` (displacement, peak) |
| ``freq_hz`` | the frequencies, ascending |
| ``threshold_db`` | the threshold at each frequency, in ``reference`` |
| ``ci_db`` | ``[[lo, hi], ...]`` per frequency, or null |
| ``procedure`` | how it was measured (e.g. ``staircase 2-down 1-up``, ``quest+``, ``simulated``) |
| ``protocol_sha256`` | the protocol file's SHA-256 (``""`` for a simulated curve) |
| ``time_utc`` | ISO 8601 UTC time it was measured |

``save_curve`` writes the file atomically (``write_text_atomic``, as ``plan.json``); a
curve for the same (modality, waveform, point) replaces the old one. ``load_curves``
validates (one ``UserError`` naming the file, the key and the fix) and ``threshold_at``
interpolates a curve linearly in log-frequency, refusing a frequency more than
``FREQ_TOLERANCE_OCT`` outside the measured range (no silent extrapolation).
"""

from __future__ import annotations

import json
import math
import time
from pathlib import Path
from typing import Any

import numpy as np

from console.plugin_api import UserError, write_text_atomic

from .textfiles import read_json

FILE_NAME = "thresholds.json"
MODALITIES = ("vibrotactile", "electrovibration")
WAVEFORMS = ("sine", "square", None)
REFERENCES = ("dB re 1 V", "dB re 1 um")
KEYS = (
    "modality",
    "waveform",
    "point",
    "reference",
    "freq_hz",
    "threshold_db",
    "ci_db",
    "procedure",
    "protocol_sha256",
    "time_utc",
)
#: how far outside its measured range (octaves) a curve is held at its end value
FREQ_TOLERANCE_OCT = 0.25
MAX_POINTS = 1000
FIX = "rerun the threshold protocol or restore the file"


def curve_path(folder: Path) -> Path:
    """The threshold file of the participant folder ``folder``."""
    return Path(folder) / FILE_NAME


def _bad(fix: str, where: str, key: str, problem: str) -> UserError:
    return UserError(f"{where}: {key} {problem}; {fix}")


def _numbers(fix: str, where: str, key: str, value: Any) -> list[float]:
    if not isinstance(value, list) or not value or len(value) > MAX_POINTS:
        raise _bad(fix, where, key, f"must be a list of 1..{MAX_POINTS} numbers, not {value!r:.60}")
    out = []
    for v in value:
        if isinstance(v, bool) or not isinstance(v, (int, float)) or not math.isfinite(v):
            raise _bad(fix, where, key, f"holds {v!r:.30}, not a finite number")
        out.append(float(v))
    return out


def check_curve(curve: Any, where: str, fix: str = FIX) -> dict[str, Any]:
    """``curve`` validated and normalised (floats, frequencies ascending); ``where`` names
    it in the one-line refusal."""
    if not isinstance(curve, dict):
        raise _bad(fix, where, "curve", f"must be an object, not {type(curve).__name__}")
    missing = [k for k in KEYS if k not in curve and k != "time_utc"]
    if missing:
        raise _bad(
            fix,
            where,
            missing[0],
            "is missing" + (f" (also {', '.join(missing[1:])})" if missing[1:] else ""),
        )
    out = dict(curve)
    for key, allowed in (
        ("modality", MODALITIES),
        ("waveform", WAVEFORMS),
        ("reference", REFERENCES),
    ):
        if out[key] not in allowed:
            names = ", ".join("null" if a is None else repr(a) for a in allowed)
            raise _bad(fix, where, key, f"is {out[key]!r:.40}, not one of {names}")
    if out["modality"] == "electrovibration" and out["reference"] != "dB re 1 V":
        raise _bad(fix, where, "reference", "of an electrovibration curve must be 'dB re 1 V'")
    if out["point"] is not None and not (isinstance(out["point"], str) and out["point"]):
        raise _bad(fix, where, "point", f"is {out['point']!r:.40}, not a grid point id or null")
    for key in ("procedure", "protocol_sha256"):
        if not isinstance(out[key], str):
            raise _bad(fix, where, key, f"is {out[key]!r:.40}, not a string")
    t = out.get("time_utc") or time.strftime("%Y-%m-%dT%H:%M:%SZ", time.gmtime())
    if not isinstance(t, str):
        raise _bad(fix, where, "time_utc", f"is {t!r:.40}, not an ISO 8601 time")
    out["time_utc"] = t
    freq = _numbers(fix, where, "freq_hz", out["freq_hz"])
    thr = _numbers(fix, where, "threshold_db", out["threshold_db"])
    if len(thr) != len(freq):
        raise _bad(fix, where, "threshold_db", f"has {len(thr)} values for {len(freq)} freq_hz")
    if min(freq) <= 0:
        raise _bad(fix, where, "freq_hz", "must be above 0 Hz")
    ci = out["ci_db"]
    cis: list[list[float]] | None = None
    if ci is not None:
        if not isinstance(ci, list) or len(ci) != len(freq):
            raise _bad(fix, where, "ci_db", f"must be null or {len(freq)} [lo, hi] pairs")
        cis = []
        for pair in ci:
            lo_hi = _numbers(fix, where, "ci_db", pair)
            if len(lo_hi) != 2 or lo_hi[0] > lo_hi[1]:
                raise _bad(
                    fix, where, "ci_db", f"holds {pair!r:.40}, not a [lo, hi] pair with lo <= hi"
                )
            cis.append(lo_hi)
    order = sorted(range(len(freq)), key=freq.__getitem__)
    if len(set(freq)) != len(freq):
        raise _bad(fix, where, "freq_hz", "holds a frequency twice")
    out["freq_hz"] = [freq[i] for i in order]
    out["threshold_db"] = [thr[i] for i in order]
    out["ci_db"] = None if cis is None else [cis[i] for i in order]
    return out


def _same(a: dict[str, Any], b: dict[str, Any]) -> bool:
    return all(a[k] == b[k] for k in ("modality", "waveform", "point"))


def load_curves(folder: Path) -> list[dict[str, Any]]:
    """The validated curves of the participant folder ``folder`` (``[]`` when it has no
    threshold file); a malformed file is one ``UserError`` naming it, the key and the fix."""
    path = curve_path(folder)
    if not path.exists():
        return []
    data = read_json(path, what="threshold file", fix=FIX)
    if not isinstance(data, dict) or not isinstance(data.get("curves"), list):
        raise _bad(FIX, str(path), "curves", "is missing or not a list")
    curves: list[dict[str, Any]] = []
    for i, c in enumerate(data["curves"]):
        curve = check_curve(c, f"{path}: curves[{i}]")
        if any(_same(curve, o) for o in curves):
            raise _bad(
                FIX, f"{path}: curves[{i}]", "modality/waveform/point", "repeats an earlier curve"
            )
        curves.append(curve)
    return curves


def save_curve(folder: Path, curve: dict) -> Path:
    """Add ``curve`` to ``folder``'s threshold file (a curve for the same modality,
    waveform and point is replaced), written atomically. Returns the file's path."""
    folder = Path(folder)
    new = check_curve(
        curve, f"{curve_path(folder)}: new curve", "fix the curve given to save_curve"
    )
    curves = [c for c in load_curves(folder) if not _same(c, new)] + [new]
    text = json.dumps({"participant": folder.name, "curves": curves}, indent=1, sort_keys=True)
    path = curve_path(folder)
    write_text_atomic(path, text + "\n")
    return path


def find_curve(
    curves: list[dict[str, Any]],
    modality: str,
    waveform: str | None = None,
    point: str | None = None,
) -> dict[str, Any] | None:
    """The curve for ``modality`` (and ``waveform``, ``point``): an exact match first,
    then a curve measured without a waveform or point (a ``dB re 1 um`` curve, a
    threshold at the skin, serves every point); None when there is none."""

    def score(c: dict[str, Any]) -> int | None:
        if c["modality"] != modality:
            return None
        s = 0
        if waveform is not None and c["waveform"] is not None:
            if c["waveform"] != waveform:
                return None
            s += 2
        if c["point"] is not None:
            if c["point"] == point:
                s += 1
            elif c["reference"] != "dB re 1 um":
                return None  # volts at one point say nothing of another point
        return s

    scored = [(score(c), c) for c in curves]
    usable = [(s, c) for s, c in scored if s is not None]
    return max(usable, key=lambda sc: sc[0])[1] if usable else None


def interpolate_db(curve: dict[str, Any], freq_hz: float, where: str = "threshold curve") -> float:
    """``curve``'s threshold at ``freq_hz``: linear in log-frequency between measured
    points, the end value within ``FREQ_TOLERANCE_OCT``; farther out one ``UserError``."""
    f = np.asarray(curve["freq_hz"], dtype=float)
    t = np.asarray(curve["threshold_db"], dtype=float)
    lo, hi = f[0] * 2**-FREQ_TOLERANCE_OCT, f[-1] * 2**FREQ_TOLERANCE_OCT
    if not lo <= freq_hz <= hi:
        raise UserError(
            f"{where}: {freq_hz:g} Hz is outside the measured {f[0]:g}..{f[-1]:g} Hz "
            f"(+- {FREQ_TOLERANCE_OCT:g} octave); measure the threshold at {freq_hz:g} Hz "
            "or give the level in volts"
        )
    return float(np.interp(np.log(freq_hz), np.log(f), t))


def threshold_at(
    curves: list[dict[str, Any]],
    modality: str,
    freq_hz: float,
    waveform: str | None = None,
    point: str | None = None,
) -> float:
    """The threshold (dB, in its curve's ``reference``) for ``modality`` at ``freq_hz``;
    one ``UserError`` when there is no such curve or the frequency is outside it."""
    curve = find_curve(curves, modality, waveform, point)
    if curve is None:
        what = " ".join(x for x in (modality, waveform or "", f"at {point}" if point else "") if x)
        raise UserError(f"no {what} threshold curve; run a threshold protocol first")
    return interpolate_db(curve, freq_hz, f"{modality} threshold curve")
