"""The runs read back for the analysis: ``load(paths)`` -> ``Study``.

Each participant's folder is read through the loaders of ``records`` and ``events``
(``plan.json``, ``participant.json``, ``trials.jsonl``, each checked against its schema
and the events against the plan), so the analysis sees only well-formed records: the last
``done`` per trial (its trial's columns completed from the plan it agrees with) and the
``questionnaire`` lines. A line a crash cut short is skipped and said in the notes.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

from console.plugin_api import UserError

from . import records
from .events import checked_events
from .records import TRIAL_COLUMNS
from .words import CLI, Words


@dataclass
class Study:
    """Everything read from the folders: one experiment."""

    experiment: str
    participants: dict[str, dict[str, Any]]
    plans: dict[str, dict[str, Any]]
    trials: Any  # pandas DataFrame of the done records
    questionnaire: Any  # pandas DataFrame of the questionnaire lines
    notes: list[str] = field(default_factory=list)
    #: how the analysis's lines name a fix (the CLI's flags or the screen's fields)
    words: Words = CLI


def _has_plan(d: Path) -> bool:
    p = d / "plan.json"
    return p.exists() or p.is_symlink()  # what it is, the loader checks


def participant_dirs(paths: list[Path], words: Words = CLI) -> list[Path]:
    """Each path is a participant's folder (it holds ``plan.json``) or a study's
    ``--out`` folder (its sub-folders that do)."""
    out: list[Path] = []
    for p in paths:
        p = Path(p).expanduser()
        if p.exists() and not p.is_dir():
            raise UserError(f"{p}: is a file, not a folder; {words.runs}")
        if not p.is_dir():
            raise UserError(f"{p}: no such folder; {words.runs}")
        if _has_plan(p):
            out.append(p)
            continue
        subs = sorted(d for d in p.iterdir() if d.is_dir() and _has_plan(d))
        if not subs:
            raise UserError(f"{p}: no participant folder (P01/plan.json ...) in it; {words.runs}")
        out.extend(subs)
    return list(dict.fromkeys(out))


def _completed(e: dict[str, Any], trial: dict[str, Any]) -> dict[str, Any]:
    """A ``done`` record with its trial's columns (which it agrees with) filled in."""
    stim = trial["stimulus"]
    base = {k: trial.get(k) for k in TRIAL_COLUMNS}
    base["stimulus"] = stim
    if records.stimulus_kind(stim) == "knob":
        base |= {"sectors": stim["sectors"], "distance_deg": stim["distance_deg"]}
    return base | e


def _lines(numbers: list[int]) -> str:
    shown = ", ".join(map(str, numbers[:5])) + (" ..." if len(numbers) > 5 else "")
    return f"line{'s' if len(numbers) > 1 else ''} {shown}"


def load(
    paths: list[Path],
    *,
    exclude: tuple[str, ...] = (),
    experiment: str | None = None,
    words: Words = CLI,
) -> Study:
    """The study in ``paths`` (one experiment; participants in ``exclude`` left out; with
    ``experiment``, only the participants of that experiment; ``words``: how its lines
    name a fix)."""
    import pandas as pd

    dirs = participant_dirs(paths, words)
    done, quest, parts, plans, notes, twice = [], [], {}, {}, [], []
    exps: dict[str, list[str]] = {}
    for d in dirs:
        plan = records.load_plan(d / "plan.json", words)
        pid = str(plan.get("participant") or d.name)
        if experiment is not None and plan["experiment"] != experiment:
            continue
        if pid in exclude:
            notes.append(f"{pid}: left out (--exclude)")
            continue
        exps.setdefault(plan["experiment"], []).append(pid)
        if pid in plans:
            twice.append(f"{d}: participant {pid} appears twice; give each folder once")
            continue
        plans[pid] = plan
        parts[pid] = records.load_participant(d / "participant.json", words, pid=pid) or {"id": pid}
        events, torn = checked_events(d / "trials.jsonl", {**plan, "participant": pid})
        if torn:
            notes.append(
                f"{pid}: trials.jsonl {_lines(torn)} cut short by a crash (skipped; the "
                "run repeated what they held)"
            )
        last: dict[int, dict] = {}
        for e in events:
            if e["event"] == "done":
                last[e["trial"]] = _completed(e, plan["trials"][e["trial"]])
            elif e["event"] == "questionnaire":
                quest.append({k: e.get(k) for k in ("condition", "category", "item", "score")})
                quest[-1]["participant"] = pid
                quest[-1]["after_trial"] = e["after_trial"]
        done.extend(last.values())
        total = len(plan["trials"])
        if len(last) < total:
            notes.append(f"{pid}: {len(last)}/{total} trials done (run not finished)")
    if len(exps) > 1:
        raise UserError(
            "the folders hold different experiments ("
            + "; ".join(f"{k}: {', '.join(v)}" for k, v in exps.items())
            + "); analyse one experiment at a time"
        )
    if twice:
        raise UserError(twice[0])
    if not exps:
        what = f" of {experiment}" if experiment else ""
        raise UserError(
            f"{', '.join(map(str, paths))}: no participant{what} left to analyse; run one first"
        )
    exp = next(iter(exps))
    trials = pd.DataFrame(done)
    if trials.empty:
        raise UserError(f"{', '.join(map(str, paths))}: no trial is done yet; run some first")
    q = pd.DataFrame(quest)
    if not q.empty:  # the last answer per participant, condition and item
        q = q.drop_duplicates(["participant", "after_trial", "category", "item"], keep="last")
    return Study(exp, parts, plans, trials, q, notes, words)
