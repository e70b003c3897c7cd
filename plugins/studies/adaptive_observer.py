"""Simulated observers of the adaptive procedures: known psychometric functions.

``draw(protocol, participant_seed)``: an observer's parameters, drawn from its seed and
the protocol's ``[observer]`` table and stored in ``participant.json`` (``observer``):
per track (frequency x waveform) the threshold ``t`` = nominal + an observer offset
N(0, ``offset_sd_db``) + a per-frequency shift N(0, ``freq_sd_db``), one ``slope`` and
``lapse`` (uniform in their ranges) and, in yes/no, a false-alarm rate; the family.

``respond(params, track, task, played_peaks_db, target, key)``: the answer to a trial from
the levels actually played (each interval's peak, from the ``OutputPlan`` the gate
accepted). n-AFC: correct with ``p = 1/n + (1 - 1/n - lapse) F(level)`` (the target
interval is answered), else one of the other intervals at random; yes/no: "yes" with
``false_alarm + (1 - false_alarm - lapse) F(level)``; a JND: ``F`` of the increment of the
target over the reference interval. Seeded by ``key`` (participant seed, trial, attempt).
"""

from __future__ import annotations

import hashlib
import math
from typing import Any

import numpy as np

from . import adaptive_pf as pf


def _rng(*keys: Any) -> np.random.Generator:
    h = hashlib.sha256(":".join(map(str, keys)).encode()).digest()
    return np.random.default_rng(int.from_bytes(h[:8], "big"))


def draw(protocol: Any, participant_seed: int) -> dict[str, Any]:
    """The observer's parameters (JSON values)."""
    o = protocol.observer
    rng = _rng(participant_seed, protocol.name, "observer")
    offset = float(rng.normal(0.0, o["offset_sd_db"])) if o["offset_sd_db"] > 0 else 0.0
    tracks = {}
    for name, f, w in protocol.tracks:
        k = protocol.stimulus["freq_hz"].index(f)
        shift = float(rng.normal(0.0, o["freq_sd_db"])) if o["freq_sd_db"] > 0 else 0.0
        t = o["threshold_db"][w][k] + offset + shift
        if o["family"] == "weibull_linear":
            t = max(t, 0.05)  # an increment threshold stays above 0 dB
        tracks[name] = {"threshold_db": round(t, 6)}
    return {
        "model": "psychometric (plugins/studies/adaptive_observer.py)",
        "family": o["family"],
        "slope": round(float(rng.uniform(*o["slope"])), 6),
        "lapse": round(float(rng.uniform(*o["lapse"])), 6),
        "false_alarm": round(float(rng.uniform(*o["false_alarm"])), 6),
        "tracks": tracks,
    }


def guess_of(params: dict[str, Any], task: str) -> float:
    return pf.GUESS.get(task, params["false_alarm"])


def p_answer(params: dict[str, Any], track: str, task: str, level_db: float) -> float:
    """P(correct) (n-AFC) or P(yes) (yes/no) at ``level_db``: the observer's truth."""
    t = params["tracks"][track]["threshold_db"]
    return float(
        pf.p_correct(
            level_db, params["family"], t, params["slope"], guess_of(params, task), params["lapse"]
        )
    )


def respond(
    params: dict[str, Any],
    track: str,
    task: str,
    peaks_db: list[float],
    target: int,
    key: tuple[Any, ...],
    jnd: bool = False,
) -> str:
    """The answer: the interval chosen (``"1"``, ``"2"``, ``"3"``) or ``yes``/``no``."""
    rng = _rng(*key, "answer")
    u, pick = rng.random(), rng.random()
    if task == "yes_no":
        return "yes" if u < p_answer(params, track, task, peaks_db[0]) else "no"
    n = len(peaks_db)
    if jnd:
        others = [x for i, x in enumerate(peaks_db) if i != target]
        x = peaks_db[target] - max(others)
    else:
        x = peaks_db[target]
    x = x if math.isfinite(x) else -1e9
    if u < p_answer(params, track, task, x):
        return str(target + 1)
    wrong = [i for i in range(n) if i != target]
    return str(wrong[int(pick * len(wrong))] + 1)
