"""What a results folder holds of one participant's run of one protocol, and how big a
run is before it starts: the Studies screen shows the first when the protocol, the
participant or the folder changes (never the previous choice's progress), and asks
before a long run (``LONG_S``) with the second (a first run's time from its stimuli).

A fixed plan's run is ``plan.json`` and ``trials.jsonl``; an adaptive one's
``adaptive.json`` and ``adaptive_trials.jsonl`` (``adaptive_run``). A run of another
protocol in the participant's folder is none of this protocol's (starting says why).
"""

from __future__ import annotations

import json
import statistics
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

from console.plugin_api import UserError
from console.plugin_api.tui import left_words

from . import adaptive_protocol as ap
from . import protocol as protocols
from .events import read_events
from .store import RunFiles, participant_dir, progress

#: a run estimated to take longer than this asks first (``s`` again starts it)
LONG_S = 300.0
#: the seconds a person is taken to answer a trial in an estimate before any run
ANSWER_S = 1.0
#: the earlier runs' trials read for their pace at most (the folder's first ones)
PACE_FILES = 20
#: a trial that took less than this share of its stimuli's time was fast-forwarded
REAL_TIME_SHARE = 0.9


@dataclass
class Saved:
    """A participant's run of a protocol in a folder: trials done, trials in all (an
    adaptive run: at most) and the done trials' records (for the trials table)."""

    done: int = 0
    total: int = 0
    records: list[dict[str, Any]] = field(default_factory=list)


def _lines(path: Path) -> list[dict[str, Any]]:
    """A JSON-lines file's objects (a line that is not one skipped: starting says why)."""
    out = []
    for line in path.read_text(encoding="utf-8").splitlines():
        try:
            e = json.loads(line)
        except ValueError:
            continue
        if isinstance(e, dict):
            out.append(e)
    return out


def _last_done(events: list[dict[str, Any]]) -> list[dict[str, Any]]:
    """The ``done`` records, the last one per trial, in trial order."""
    by_trial = {e["trial"]: e for e in events if e.get("event") == "done" and "trial" in e}
    return [by_trial[k] for k in sorted(by_trial)]


def saved(out: Path, pid: str, study: str) -> Saved | None:
    """``pid``'s run of ``study`` in ``out``, None without one (or one that cannot be
    read: starting says why)."""
    if not pid:
        return None
    try:
        root = participant_dir(out, pid)
        if ap.is_adaptive(study):
            proto = ap.load(study)
            run = json.loads((root / "adaptive.json").read_text(encoding="utf-8"))
            if run.get("experiment") not in (None, proto.name):
                return None
            log = root / "adaptive_trials.jsonl"
            records = _last_done(_lines(log)) if log.exists() else []
            total = len(proto.tracks) * int(proto.procedure["max_trials"])
            return Saved(len(records), total, records)
        files = RunFiles(root)
        plan = json.loads(files.plan_path.read_text(encoding="utf-8"))
        if plan.get("experiment") not in (None, protocols.load(study).name):
            return None
        events = read_events(files.trials_path) if files.trials_path.exists() else []
        st = progress(plan, events)
        return Saved(len(st.done), st.total, _last_done(events))
    except (OSError, ValueError, KeyError, TypeError, AttributeError, UserError):
        return None


@dataclass(frozen=True)
class Size:
    """A run before it starts: its trials (left, on a resume), ``at_most`` for an
    adaptive run, and their time in seconds (None: not known before it runs) and how."""

    trials: int
    at_most: bool
    seconds: float | None
    basis: str
    #: ``seconds`` is a floor (the stimuli alone), not a pace measured
    at_least: bool = False

    @property
    def long(self) -> bool:
        return self.seconds is not None and self.seconds > LONG_S

    def words(self) -> str:
        """``up to 1,280 trials, about 30 min (...)``."""
        n = f"{'up to ' if self.at_most else ''}{self.trials:,} trial{'s' * (self.trials != 1)}"
        if self.seconds is None:
            return n
        about = left_words(self.seconds).removesuffix(" left")
        if self.at_least:
            about = "at least " + about.removeprefix("about ")
        return f"{n}, {about} ({self.basis})" if self.basis else f"{n}, {about}"


def stimulus_seconds(study: str, profile: Any) -> float | None:
    """The seconds a trial of the fixed plan ``study`` plays its stimulus on ``profile``
    (a flow: its two parts and their gap, as the vibrotactile effects render them);
    None when not known before it runs (the knob: until the selection rests)."""
    try:
        stim = protocols.load(study).stimulus
        if stim not in ("flow", "hand_flow"):
            return None
        part_s = float(profile.get("vibrotactile.part_s"))
        return 2 * part_s + float(profile.get("vibrotactile.gap_ms")) / 1e3
    except (OSError, UserError, TypeError, ValueError):
        return None


def run_size(
    study: str, out: Path, pid: str, simulate: bool, stimulus_s: float | None = None
) -> Size:
    """How big ``pid``'s run of ``study`` in ``out`` is before ``s`` starts it: a fixed
    plan's time at the pace of the folder's earlier runs, without any from its stimuli
    (``stimulus_s`` a trial, ``stimulus_seconds``; a person also answers)."""
    before = saved(out, pid, study)
    done = before.done if before else 0
    if ap.is_adaptive(study):
        proto = ap.load(study)
        trials = max(len(proto.tracks) * int(proto.procedure["max_trials"]) - done, 0)
        st, k = proto.stimulus, proto.n_intervals
        stim_s = k * st["interval_s"] + (k - 1) * st["gap_s"]
        if simulate:
            return Size(trials, True, trials * stim_s, f"the stimuli, {stim_s:g} s a trial")
        basis = f"the stimuli and {ANSWER_S:g} s to answer, {stim_s + ANSWER_S:g} s a trial"
        return Size(trials, True, trials * (stim_s + ANSWER_S), basis)
    trials = max(protocols.load(study).n_trials - done, 0)
    pace = earlier_pace(out, study, simulate, stimulus_s)
    if pace is None and stimulus_s is not None:  # a first run: the stimuli say
        if simulate:  # the console plays them in real time; its rendering adds to them
            basis = f"its stimuli play in real time, {stimulus_s:g} s a trial"
            return Size(trials, False, trials * stimulus_s, basis, at_least=True)
        a_s = ANSWER_S
        basis = f"the stimuli and {a_s:g} s to answer, {stimulus_s + a_s:g} s a trial"
        return Size(trials, False, trials * (stimulus_s + a_s), basis)
    if pace is None:
        return Size(trials, False, None, "")
    basis = f"at the pace of the earlier runs in the folder, {pace:.1f} s a trial"
    return Size(trials, False, trials * pace, basis)


def earlier_pace(
    out: Path, study: str, simulate: bool, stimulus_s: float | None = None
) -> float | None:
    """The median seconds a trial took in the folder's earlier runs of ``study`` (by
    participants as simulated as this one), None without any. A trial shorter than
    its stimuli (``stimulus_s``) did not play them in real time as the console does (a
    shell's ``haptable study run --simulate`` fast-forwards the twin): not this run's
    pace, not counted."""
    try:
        name = protocols.load(study).name
        paths = sorted(Path(out).expanduser().glob("*/trials.jsonl"))[:PACE_FILES]
    except (OSError, UserError):
        return None
    took = []
    for path in paths:
        try:
            events = _lines(path)
        except OSError:
            continue
        for e in events:
            if e.get("event") != "done" or e.get("experiment") not in (None, name):
                continue
            if bool(e.get("simulated")) != simulate:
                continue
            t0, t1 = e.get("t_start"), e.get("t_end")
            if not (isinstance(t0, int | float) and isinstance(t1, int | float) and t1 >= t0):
                continue
            if stimulus_s is None or t1 - t0 >= REAL_TIME_SHARE * stimulus_s:
                took.append(float(t1) - float(t0))
    return statistics.median(took) if took else None
