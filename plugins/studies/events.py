"""``trials.jsonl`` checked line by line against its schema and its plan.

Every line is an event of ``records.EVENT`` (``start``, ``done``, ``interrupted``,
``questionnaire``) of this folder's participant and experiment; a ``trial`` is one of the
plan's, and a ``done`` record agrees with the plan's trial (phase, place, direction,
condition, stimulus), answers one of the plan's responses and is ``correct`` exactly when
it answered the trial's direction; a questionnaire line follows one of the plan's
questionnaires, with a score on its scale. A line cut short by a crash is skipped (and
reported); anything else wrong is one ``UserError`` naming the file, the line, the key
and the value. Nothing is ever rewritten: the fix is the user's (restore or delete the
line).
"""

from __future__ import annotations

from pathlib import Path
from typing import Any

from console.plugin_api import UserError

from . import textfiles
from .records import COMMON, EVENT, TRIAL_COLUMNS, _show, check_record

#: the fix of a bad line, at a shell and on the screen alike (the file is edited by hand)
FIX = "restore the line as the run wrote it, or delete it (a resume asks its trial or item again)"
WHAT = "trials file (trials.jsonl)"
#: the fix of a file that cannot be read at all
FILE_FIX = "restore the file the run wrote, or start the participant in a new folder (--out)"


def read_events(path: Path) -> list[dict[str, Any]]:
    """The events of a ``trials.jsonl`` checked as JSON objects only (no plan): a torn
    line (a crash mid-write) is skipped, any other bad line is a ``UserError``."""
    return [
        e
        for _, e in textfiles.jsonl_lines(path, what=WHAT, fix=FIX, file_fix=FILE_FIX)
        if e is not None
    ]


def checked_events(path: Path, plan: dict[str, Any]) -> tuple[list[dict[str, Any]], list[int]]:
    """The events of ``path`` checked against ``plan`` (checked with
    ``records.check_plan``) and the numbers of the torn lines skipped."""
    fix = FIX
    events: list[dict[str, Any]] = []
    torn: list[int] = []
    for n, e in textfiles.jsonl_lines(path, what=WHAT, fix=fix, file_fix=FILE_FIX):
        if e is None:
            torn.append(n)
            continue
        _check(e, plan, f"{path}: line {n}", fix)
        events.append(e)
    return events, torn


def load_events(path: Path, plan: dict[str, Any]) -> list[dict[str, Any]]:
    """The events of ``path`` checked against ``plan`` (torn lines skipped)."""
    return checked_events(path, plan)[0]


def _check(e: dict[str, Any], plan: dict[str, Any], where: str, fix: str) -> None:
    check_record(e, COMMON, where, fix)
    kind = e["event"]
    check_record(e, EVENT[kind], where, fix)
    for key in ("experiment", "participant"):
        want = plan.get(key)
        if want is not None and e[key] != want:
            raise UserError(
                f"{where}: {key} = {_show(e[key])} but this folder's plan.json has {_show(want)}; {fix}"
            )
    trials = plan["trials"]
    if kind == "questionnaire":
        _questionnaire(e, plan, where, fix)
        return
    i = e["trial"]
    if not 0 <= i < len(trials):
        raise UserError(
            f"{where}: trial = {i}: not in the plan (plan.json has trials 0..{len(trials) - 1}); "
            f"{fix}"
        )
    if kind == "done":
        _done(e, trials[i], plan, where, fix)


def _done(e: dict[str, Any], t: dict[str, Any], plan: dict[str, Any], where: str, fix: str) -> None:
    i = t["index"]
    for key in TRIAL_COLUMNS:
        if key in e and e[key] != t.get(key):
            raise UserError(
                f"{where}: {key} = {_show(e[key])} but plan.json's trial {i} has "
                f"{_show(t.get(key))}; {fix}"
            )
    if "stimulus" in e and t["stimulus"] and e["stimulus"] != t["stimulus"]:
        raise UserError(
            f"{where}: stimulus = {_show(e['stimulus'])} is not plan.json's trial {i} "
            f"stimulus {_show(t['stimulus'])}; {fix}"
        )
    stim = t["stimulus"]
    for key in ("sectors", "distance_deg", "condition"):
        if key in e and key in stim and e[key] != stim[key]:
            raise UserError(
                f"{where}: {key} = {_show(e[key])} but plan.json's trial {i} has "
                f"{_show(stim[key])}; {fix}"
            )
    responses = plan.get("responses")
    r = e.get("response")
    if r is not None and responses is not None and r not in responses:
        allowed = ", ".join(responses) if responses else "none (null)"
        raise UserError(f"{where}: response = {_show(r)}: the plan's answers are {allowed}; {fix}")
    direction = t.get("direction")
    if r is not None and direction is not None and e["correct"] != (r == direction):
        raise UserError(
            f"{where}: correct = {_show(e['correct'])} but response {_show(r)} "
            f"{'is' if r == direction else 'is not'} the direction {_show(direction)}; {fix}"
        )


def _questionnaire(e: dict[str, Any], plan: dict[str, Any], where: str, fix: str) -> None:
    after = e["after_trial"]
    qs = plan.get("questionnaires")
    if qs is None:  # a plan without them: any trial, the largest scale
        scale = 11
        if not 0 <= after < len(plan["trials"]):
            raise UserError(
                f"{where}: after_trial = {after}: not in the plan (trials 0.."
                f"{len(plan['trials']) - 1}); {fix}"
            )
    else:
        q = next((q for q in qs if q["after_trial"] == after), None)
        if q is None:
            at = ", ".join(str(q["after_trial"]) for q in qs) or "no trial"
            raise UserError(
                f"{where}: after_trial = {after}: plan.json asks the questionnaire after {at}; "
                f"{fix}"
            )
        scale = q["scale"]
        if not any((it["category"], it["item"]) == (e["category"], e["item"]) for it in q["items"]):
            raise UserError(
                f"{where}: category {_show(e['category'])} item {e['item']}: not an item of the "
                f"questionnaire after trial {after}; {fix}"
            )
        if "condition" in e and e["condition"] != q["condition"]:
            raise UserError(
                f"{where}: condition = {_show(e['condition'])} but the questionnaire after "
                f"trial {after} is for {_show(q['condition'])}; {fix}"
            )
    if e["score"] > scale:
        raise UserError(f"{where}: score = {e['score']}: give 1..{scale}; {fix}")
