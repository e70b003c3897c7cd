"""Adaptive protocols as data: ``studies/threshold_*.toml``, ``jnd_amplitude.toml``.

A protocol with a ``[procedure]`` table is adaptive (``is_adaptive``). Its tables:

- ``[study]``: ``name``, ``title``, ``seed``;
- ``[stimulus]``: ``modality`` (``vibrotactile`` | ``electrovibration``), ``reference``
  (``dB re 1 V`` | ``dB re 1 um``: the map's predicted displacement at ``point``,
  vibrotactile only), ``point`` (grid point id) and ``actuator`` (``PALL``, ``PA`` ..),
  ``freq_hz``, ``waveforms`` (``sine``, ``square``), ``interval_s``, ``ramp_ms``,
  ``gap_s`` (between intervals) and, for a JND, ``reference_db`` (the reference level);
- ``[procedure]``: ``method`` (``quest+`` | ``staircase``), ``task`` (``yes_no`` |
  ``2afc`` | ``3afc``), ``measure`` (``detection`` | ``jnd``: the level is the increment
  over ``reference_db``), ``max_trials`` per track, ``interleave`` (tracks in a seeded
  random order, else one after the other); QUEST+: ``family``, ``levels_db``,
  ``thresholds_db`` (``[from, to, step]``), ``slopes``, ``lapses``, ``false_alarms``
  (yes/no); staircase: ``down``, ``start_db``, ``step_db``, ``halve_after``,
  ``min_step_db``, ``stop_reversals``, ``threshold_reversals``;
- ``[observer]``: the simulated observers (``--simulate``): ``family``, the nominal
  ``threshold_db`` per frequency (a list, or a table per waveform), ``offset_sd_db``
  (per observer), ``freq_sd_db`` (per frequency), ``slope``, ``lapse``, ``false_alarm``
  (``[lo, hi]``, drawn uniformly).

One track per frequency x waveform. Every mistake is one ``UserError`` naming the file,
the key, the value and the fix (``protocol._fields``, as the fixed-plan protocols).
"""

from __future__ import annotations

import hashlib
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np

from console.plugin_api import Field, UserError, parse_toml_text

from . import adaptive_pf as pf
from . import protocol as protocols
from . import textfiles

TABLES = {"study", "stimulus", "procedure", "observer"}
STUDY = {
    "name": Field("str", help="the protocol's short name"),
    "title": Field("str", "", help="what the experimenter reads"),
    "seed": Field("int", 0, min=0, help="seeds the observers' draws and the orders"),
}
STIMULUS = {
    "modality": Field("str", choices=("vibrotactile", "electrovibration"), help="the actuator"),
    "reference": Field("str", choices=("dB re 1 V", "dB re 1 um"), help="what 0 dB is"),
    "point": Field("int", -1, min=-1, help="the grid point id (vibrotactile)"),
    "actuator": Field("str", "PALL", choices=("PALL", "PA", "PB", "PC", "PD"), help="excitation"),
    "freq_hz": Field("floats", min=1, max=5000, min_length=1, help="the frequencies"),
    "waveforms": Field("strs", ["sine"], help="sine and/or square"),
    "interval_s": Field("float", 0.5, min=0.05, max=5, help="one interval's length"),
    "ramp_ms": Field("float", 50.0, min=1, max=1000, help="linear ramps at both ends"),
    "gap_s": Field("float", 0.4, min=0, max=5, help="silence between intervals"),
    "reference_db": Field("float", 0.0, min=-200, max=200, help="a JND's reference level"),
}
PROCEDURE = {
    "method": Field("str", choices=("quest+", "staircase"), help="the adaptive method"),
    "task": Field("str", choices=pf.TASKS, help="the task"),
    "measure": Field("str", "detection", choices=("detection", "jnd"), help="what is measured"),
    "max_trials": Field("int", 50, min=1, max=2000, help="trials per track at most"),
    "interleave": Field("bool", True, help="tracks in a seeded random order"),
    "family": Field("str", "weibull", choices=pf.FAMILIES, help="QUEST+'s psychometric family"),
    "levels_db": Field("floats", [-40.0, 40.0, 1.0], length=3, help="[from, to, step] dB"),
    "thresholds_db": Field("floats", [-40.0, 40.0, 1.0], length=3, help="[from, to, step] dB"),
    "slopes": Field("floats", [1.5, 2, 3, 4, 6, 8], min=0.01, min_length=1, help="slope grid"),
    "lapses": Field("floats", [0.0, 0.02, 0.04], min=0, max=0.2, min_length=1, help="lapses"),
    "false_alarms": Field("floats", [0.0, 0.02, 0.05], min=0, max=0.5, min_length=1, help="yes/no"),
    "down": Field("int", 2, min=1, max=4, help="correct answers in a row to step down"),
    "start_db": Field("float", 20.0, min=-200, max=200, help="the first level"),
    "step_db": Field("float", 4.0, min=0.01, max=40, help="the first step"),
    "halve_after": Field("int", 2, min=0, max=10, help="reversals at which the step halves"),
    "min_step_db": Field("float", 0.5, min=0.01, max=40, help="the smallest step"),
    "stop_reversals": Field("int", 12, min=2, max=100, help="reversals to stop after"),
    "threshold_reversals": Field("int", 8, min=2, max=100, help="last reversals averaged"),
}
OBSERVER = {
    "family": Field("str", "weibull", choices=pf.FAMILIES, help="the observers' family"),
    "offset_sd_db": Field("float", 3.0, min=0, max=40, help="per-observer threshold shift"),
    "freq_sd_db": Field("float", 1.5, min=0, max=40, help="per-frequency threshold shift"),
    "slope": Field("floats", [2.0, 6.0], length=2, min=0.01, help="[lo, hi] drawn uniformly"),
    "lapse": Field("floats", [0.0, 0.04], length=2, min=0, max=0.2, help="[lo, hi]"),
    "false_alarm": Field("floats", [0.0, 0.05], length=2, min=0, max=0.5, help="[lo, hi]"),
}


@dataclass(frozen=True)
class AdaptiveProtocol:
    name: str
    title: str
    seed: int
    stimulus: dict[str, Any]
    procedure: dict[str, Any]
    observer: dict[str, Any]  # with "threshold_db": {waveform: [per frequency]}
    path: str = ""
    sha256: str = ""

    @property
    def tracks(self) -> list[tuple[str, float, str]]:
        """``(name, freq_hz, waveform)`` of every track, waveform by waveform."""
        return [
            (track_name(f, w), f, w)
            for w in self.stimulus["waveforms"]
            for f in self.stimulus["freq_hz"]
        ]

    @property
    def n_intervals(self) -> int:
        return pf.INTERVALS[self.procedure["task"]]

    def size_line(self, person: bool = True, answer_s: float = 1.0) -> str:
        """What a run is before it starts: its trials at most and, for a person, their
        time at the stimulus' pace (intervals and gaps, ``answer_s`` to answer each)."""
        st, n = self.stimulus, len(self.tracks)
        most = n * self.procedure["max_trials"]
        line = f"at most {most} trials ({n} tracks x {self.procedure['max_trials']})"
        if not person:
            return line
        k = self.n_intervals
        trial_s = k * st["interval_s"] + (k - 1) * st["gap_s"] + answer_s
        return f"{line}, about {trial_s:.1f} s each: up to {most * trial_s / 60:.0f} min"


def track_name(freq_hz: float, waveform: str) -> str:
    return f"{waveform}_{freq_hz:g}Hz"


def _raw(path: Path) -> tuple[dict[str, Any], str]:
    fix = "give a protocol .toml file or a name in studies/"
    data = textfiles.read_bytes(
        path, what="study protocol", fix=fix, limit=textfiles.MAX_PROTOCOL_BYTES
    )
    text = textfiles.decode(data, str(path), "save the protocol as UTF-8 text")
    return parse_toml_text(text, where=str(path), what="study protocol"), hashlib.sha256(
        data
    ).hexdigest()


def is_adaptive(name_or_path: str | Path) -> bool:
    """True when the protocol has a ``[procedure]`` table (read errors: False, so the
    fixed-plan loader reports them)."""
    try:
        raw, _ = _raw(protocols.find(name_or_path))
    except UserError:
        return False
    return isinstance(raw, dict) and "procedure" in raw


def load(name_or_path: str | Path) -> AdaptiveProtocol:
    path = protocols.find(name_or_path)
    raw, sha = _raw(path)
    return parse(raw, str(path), sha256=sha)


def _table(where: str, raw: dict, key: str, fields: dict[str, Field]) -> dict[str, Any]:
    t = raw.get(key, {})
    out = protocols._fields(where, t, fields, f"{key}.")
    protocols._unknown(
        where, t, set(fields) | ({"threshold_db"} if key == "observer" else set()), f"{key}."
    )
    return out


def _grid(where: str, key: str, v: list[float]) -> np.ndarray:
    lo, hi, step = v
    if not (step > 0 and hi > lo and (hi - lo) / step <= 2000):
        raise UserError(
            f"{where}: procedure.{key} = {v!r}: give [from, to, step] with from < to, step > 0 "
            "and at most 2000 steps"
        )
    return np.round(np.arange(lo, hi + step / 2, step), 9)


def parse(raw: dict[str, Any], where: str = "<protocol>", *, sha256: str = "") -> AdaptiveProtocol:
    """A checked ``AdaptiveProtocol`` from a parsed TOML document."""
    protocols._unknown(where, raw, TABLES, "")
    for key in ("study", "stimulus", "procedure"):
        if key not in raw:
            raise UserError(
                f"{where}: [{key}] is missing; add it (see studies/threshold_vibrotactile.toml)"
            )
    study = _table(where, raw, "study", STUDY)
    stim = _table(where, raw, "stimulus", STIMULUS)
    proc = _table(where, raw, "procedure", PROCEDURE)
    obs = _table(where, raw, "observer", OBSERVER)
    for w in stim["waveforms"]:
        if w not in ("sine", "square"):
            raise UserError(f"{where}: stimulus.waveforms has {w!r}: use sine and/or square")
    freqs = stim["freq_hz"]
    if len(set(freqs)) != len(freqs):
        raise UserError(f"{where}: stimulus.freq_hz = {freqs!r}: a frequency is given twice")
    if stim["modality"] == "vibrotactile" and stim["point"] < 1:
        raise UserError(
            f"{where}: stimulus.point is missing; a vibrotactile protocol names its grid point id"
        )
    if stim["modality"] == "electrovibration" and stim["reference"] != "dB re 1 V":
        raise UserError(
            f"{where}: stimulus.reference = {stim['reference']!r}: electrovibration levels are 'dB re 1 V'"
        )
    if proc["measure"] == "jnd" and proc["task"] == "yes_no":
        raise UserError(
            f"{where}: procedure.task = 'yes_no': a JND compares intervals; use 2afc or 3afc"
        )
    if 2 * stim["ramp_ms"] / 1e3 >= stim["interval_s"]:
        raise UserError(
            f"{where}: stimulus.ramp_ms = {stim['ramp_ms']:g}: two ramps must fit in interval_s"
        )
    if proc["threshold_reversals"] > proc["stop_reversals"]:
        raise UserError(
            f"{where}: procedure.threshold_reversals = {proc['threshold_reversals']}: at most stop_reversals"
        )
    proc["levels"] = _grid(where, "levels_db", proc["levels_db"])
    proc["thresholds"] = _grid(where, "thresholds_db", proc["thresholds_db"])
    if proc["measure"] == "jnd" and proc["levels"][0] < 0:
        raise UserError(
            f"{where}: procedure.levels_db = {proc['levels_db']!r}: a JND's increments start at 0 or above"
        )
    obs["threshold_db"] = _nominal(where, raw.get("observer", {}).get("threshold_db"), stim)
    return AdaptiveProtocol(
        name=study["name"],
        title=study["title"] or study["name"],
        seed=study["seed"],
        stimulus=stim,
        procedure=proc,
        observer=obs,
        path=where,
        sha256=sha256,
    )


def _nominal(where: str, v: Any, stim: dict[str, Any]) -> dict[str, list[float]]:
    """The observers' nominal threshold per waveform and frequency."""
    n = len(stim["freq_hz"])
    fix = f"give {n} numbers (one per stimulus.freq_hz), or a table of them per waveform"
    if v is None:
        raise UserError(f"{where}: observer.threshold_db is missing; {fix}")
    table = v if isinstance(v, dict) else {w: v for w in stim["waveforms"]}
    out = {}
    for w in stim["waveforms"]:
        vals = table.get(w)
        ok = isinstance(vals, list) and len(vals) == n
        ok = ok and all(isinstance(x, int | float) and not isinstance(x, bool) for x in vals)
        if not ok:
            raise UserError(f"{where}: observer.threshold_db ({w}) = {vals!r}: {fix}")
        out[w] = [float(x) for x in vals]
    return out
