"""Perceptual tables for one person: their ``thresholds.json`` in place of the population
fingertip curve of ``[perception]``.

``haptable tables build MAP --out FILE --thresholds DIR/P01/thresholds.json`` (and
``tables query``): the perceptual rule (``perceptual_rule.py``) scores every candidate at
the person's own detection threshold, so the sensation levels it weighs (``L_a =
20 log10(|H_a| V) - T(f)``, the target ``sensation_level_db``, what is felt of the passive
point) are above that person's threshold, and the tables file stores their curve in its
``rule_json``. The file is the one the threshold protocols write for a participant
(``plugins/studies/README.md``, ``thresholds.json``): its ``vibrotactile`` curve in
``dB re 1 um`` (a threshold at the skin, the tables' unit; a sine curve first, one
measured without a point before one at a point). Between its frequencies the curve is
linear in log frequency and a quarter octave beyond its ends holds the end value, as the
studies read it; a curve that does not reach every candidate bin of the tables (the
usable bins inside ``[vibrotactile] play_band_hz``) is refused in one line, never
extrapolated: measure there or narrow the band.
"""

from __future__ import annotations

import dataclasses
import math
from pathlib import Path
from typing import Any

import numpy as np

from console.plugin_api import UserError, decode, parse_json, read_bytes_capped

from .perceptual_rule import PerceptualRule

#: as ``plugins/studies/thresholds.py``: a curve holds its end value this far (octaves)
FREQ_TOLERANCE_OCT = 0.25
MAX_BYTES = 4 * 2**20
FIX = "give the thresholds.json a threshold protocol wrote (haptable study run threshold_vibrotactile)"


def _numbers(where: str, key: str, value: Any) -> list[float]:
    ok = isinstance(value, list) and len(value) >= 2
    ok = ok and all(
        isinstance(v, (int, float)) and not isinstance(v, bool) and math.isfinite(v) for v in value
    )
    if not ok:
        raise UserError(f"{where}: {key} must be a list of at least 2 finite numbers; {FIX}")
    return [float(v) for v in value]


def load_curve(path: str | Path) -> tuple[str, np.ndarray, np.ndarray]:
    """(participant, freq_hz ascending, threshold dB re 1 um) of the person's vibrotactile
    curve in ``path``; one ``UserError`` naming the file and key otherwise."""
    p = Path(path)
    data = read_bytes_capped(p, what="threshold file", fix=FIX, max_bytes=MAX_BYTES)
    doc = parse_json(decode(data or b"", str(p), FIX), str(p), FIX)
    curves = doc.get("curves") if isinstance(doc, dict) else None
    if not isinstance(curves, list):
        raise UserError(f"{p}: curves is missing or not a list; {FIX}")
    who = str(doc.get("participant") or p.parent.name)
    usable = [
        (i, c)
        for i, c in enumerate(curves)
        if isinstance(c, dict)
        and c.get("modality") == "vibrotactile"
        and c.get("reference") == "dB re 1 um"
    ]
    if not usable:
        raise UserError(
            f"{p}: {who} has no vibrotactile threshold in dB re 1 um (the tables' unit); run "
            f"`haptable study run threshold_vibrotactile --participant {who} ...` first"
        )
    i, c = min(usable, key=lambda ic: (ic[1].get("waveform") not in ("sine", None),
                                        ic[1].get("point") is not None))  # fmt: skip
    where = f"{p}: curves[{i}]"
    f = _numbers(where, "freq_hz", c.get("freq_hz"))
    t = _numbers(where, "threshold_db", c.get("threshold_db"))
    if len(f) != len(t) or min(f) <= 0 or len(set(f)) != len(f):
        raise UserError(
            f"{where}: freq_hz and threshold_db must pair distinct frequencies above 0 Hz "
            f"with one threshold each; {FIX}"
        )
    order = np.argsort(f)
    return who, np.asarray(f)[order], np.asarray(t)[order]


def personal_rule(rule: PerceptualRule, path: str | Path, freq_hz: np.ndarray) -> PerceptualRule:
    """``rule`` scoring at the person's threshold (``path``), checked to cover the
    candidate bins ``freq_hz`` (Hz) of the tables; one ``UserError`` otherwise."""
    who, f, t = load_curve(path)
    cand = np.asarray(freq_hz, float)
    lo, hi = f[0] * 2**-FREQ_TOLERANCE_OCT, f[-1] * 2**FREQ_TOLERANCE_OCT
    if cand.size and (cand.min() < lo or cand.max() > hi):
        a = max(float(cand.min()), f[0])
        b = min(float(cand.max()), f[-1])
        raise UserError(
            f"{path}: {who}'s vibrotactile threshold covers {f[0]:g}..{f[-1]:g} Hz (+- a "
            f"quarter octave), the tables' candidate bins run {cand.min():g}..{cand.max():g} "
            f"Hz; measure the threshold there, or narrow the band: [vibrotactile] "
            f"play_band_hz = [{a:g}, {b:g}]"
        )
    tip = rule.perception.fingertip_offset_db  # the rule reads the fingertip curve
    per = dataclasses.replace(
        rule.perception,
        freq_hz=tuple(float(x) for x in f),
        threshold_db_re_1um=tuple(float(x) - tip for x in t),
    )
    return dataclasses.replace(rule, perception=per)
