"""The files of a run checked against their schema: one loader per kind of file.

``load_plan`` (``plan.json``), ``load_participant`` (``participant.json``) and
``load_events`` (``trials.jsonl``, against its plan) read through ``textfiles`` (kind,
size, UTF-8, JSON) and check every key they use against the tables below (the contract of
this package's README.md), so that the runner and the analysis only ever see well-formed
records. A file that is not is one ``UserError``: the file, the line (``trials.jsonl``),
the key, the value and the fix; nothing is rewritten.

The analysis reads plans as the contract requires (``need="all"``); a resume needs what
the runner uses too (``need="run"``). Keys absent from a table are left alone.
"""

from __future__ import annotations

import json
from dataclasses import dataclass
from functools import cache
from pathlib import Path
from typing import Any

from console.plugin_api import KINDS, Field, UserError, check

from . import textfiles
from .words import CLI, Words

MAX_TRIALS = 100_000
MAX_SEED = 2**63 - 1
STIMULI = ("flow", "hand_flow", "knob")
EVENTS = ("start", "done", "interrupted", "questionnaire")
SEXES = ("female", "male", "other", "undisclosed")
HANDEDNESS = ("left", "right", "ambidextrous")
#: the trial's columns a ``done`` record repeats from its plan
TRIAL_COLUMNS = ("phase", "block", "pair", "region", "direction", "condition", "hand")


@dataclass(frozen=True)
class Key:
    """One key of a record: a ``console.core.schema`` kind (or ``dict``, ``list``,
    ``scalar``: a string or number), whether it may be null and when it is required."""

    kind: str
    need: str = ""  # "": optional; "all": always; "run": to resume a run
    null: bool = False
    min: float | None = None
    max: float | None = None
    choices: tuple[Any, ...] | None = None
    length: int | None = None

    def allowed(self) -> str:
        if self.kind in KINDS:
            what = self.field().allowed()
        else:
            what = {"dict": "an object", "list": "a list", "scalar": "a string or a number"}
            what = what[self.kind]
        return what + (" or null" if self.null else "")

    def field(self) -> Field:
        return _field(self.kind, self.min, self.max, self.choices, self.length)

    def ok(self, v: Any) -> bool:
        if v is None:
            return self.null
        if self.kind == "dict":
            return isinstance(v, dict)
        if self.kind == "list":
            return isinstance(v, list)
        if self.kind == "scalar":
            return isinstance(v, (str, int, float)) and not isinstance(v, bool)
        return check(self.field(), v)[0]


@cache
def _field(kind: str, lo: float | None, hi: float | None, choices: Any, length: Any) -> Field:
    return Field(kind, default=None, min=lo, max=hi, choices=choices, length=length)


def _show(v: Any) -> str:
    """A value as its file spells it (JSON), cut to 80 characters."""
    try:
        text = json.dumps(v, ensure_ascii=False)
    except (TypeError, ValueError):
        text = repr(v)
    return text if len(text) <= 80 else text[:77] + "..."


def check_record(
    obj: Any, keys: dict[str, Key], where: str, fix: str, *, prefix: str = "", run: bool = False
) -> dict[str, Any]:
    """``obj`` as a record of ``keys`` (a ``UserError`` naming the first bad key)."""
    if not isinstance(obj, dict):
        what = prefix.rstrip(".") or "the file"
        raise UserError(
            f"{where}: {what} is a {type(obj).__name__}, not an object (JSON {{...}}); {fix}"
        )
    for name, key in keys.items():
        if name not in obj:
            if key.need == "all" or (run and key.need == "run"):
                raise UserError(f"{where}: {prefix}{name} is missing; {fix}")
            continue
        if not key.ok(obj[name]):
            raise UserError(
                f"{where}: {prefix}{name} = {_show(obj[name])}: must be {key.allowed()}; {fix}"
            )
    return obj


def _int(lo: float | None = 0, hi: float | None = None, **kw: Any) -> Key:
    return Key("int", min=lo, max=hi, **kw)


def _str(**kw: Any) -> Key:
    return Key("str", **kw)


def _num(lo: float | None = None, **kw: Any) -> Key:
    return Key("float", min=lo, **kw)


PLAN = {
    "experiment": _str(need="all"),
    "participant": _str(need="run"),
    "seed": _int(0, need="run"),
    "stimulus": _str(need="run", choices=STIMULI),
    "responses": Key("strs", need="run"),
    "protocol_file": _str(),
    "protocol_sha256": _str(need="run"),
    "title": _str(),
    "latin_square_row": _int(null=True),
    "factors": Key("dict"),
    "trials": Key("list", need="all"),
    "questionnaires": Key("list", need="run"),
}
TRIAL = {
    "index": _int(need="all"),
    "phase": _str(need="all"),
    "stimulus": Key("dict", need="all"),
    "block": Key("scalar", null=True),
    **{k: _str(null=True) for k in TRIAL_COLUMNS[2:]},
    "replays_allowed": _int(0, null=True, need="run"),
}
STIMULUS = {
    "flow": {k: _int(need="all") for k in ("from_point", "to_point", "left", "right")},
    "hand_flow": {
        "center_mm": Key("floats", need="all", length=2),
        "direction": _str(need="all"),
        "hand": _str(need="all", choices=("left", "right")),
    },
    "knob": {
        "condition": _str(need="all"),
        "sectors": _int(2, need="all"),
        "distance_deg": _num(0, need="all"),
    },
}
QUESTIONNAIRE = {
    "after_trial": _int(need="all"),
    "condition": Key("scalar", null=True),
    "scale": _int(2, 11, need="all"),
    "items": Key("list", need="all"),
}
ITEM = {"category": _str(need="all"), "item": _int(1, need="all"), "text": _str()}
PARTICIPANT = {
    "id": _str(need="all"),
    "age": _int(1, 120),
    "sex": _str(choices=SEXES),
    "handedness": _str(choices=HANDEDNESS),
    "hand_width_cm": _num(3, max=30),
    "hand_length_cm": _num(5, max=40),
    "consent_noted": Key("bool"),
    "consent_time": _str(),
    "simulated": Key("bool", need="all"),
    "observer": Key("dict"),
}


def _fix(words: Words) -> str:
    return f"restore it or start a new {words.out}"


def stimulus_kind(stim: dict[str, Any]) -> str | None:
    """``flow``, ``hand_flow``, ``knob`` or None (a stimulus of none of them)."""
    if stim.get("task") == "knob":
        return "knob"
    kind = stim.get("effect")
    return kind if kind in ("flow", "hand_flow") else None


def check_plan(plan: Any, where: str, fix: str, *, run: bool = False) -> dict[str, Any]:
    """A plan as its schema wants it (``run``: with what the runner needs)."""
    check_record(plan, PLAN, where, fix, run=run)
    if not plan["experiment"]:
        raise UserError(f"{where}: experiment = '': name the experiment; {fix}")
    trials = plan["trials"]
    if not trials or len(trials) > MAX_TRIALS:
        raise UserError(f"{where}: {len(trials)} trials; a plan has 1..{MAX_TRIALS}; {fix}")
    want = plan.get("stimulus")
    for i, t in enumerate(trials):
        pre = f"trials[{i}]."
        check_record(t, TRIAL, where, fix, prefix=pre, run=run)
        if t["index"] != i:
            raise UserError(f"{where}: {pre}index = {_show(t['index'])}: must be {i}; {fix}")
        kind = stimulus_kind(t["stimulus"])
        if kind is None and (run or t["stimulus"]):
            raise UserError(
                f"{where}: {pre}stimulus = {_show(t['stimulus'])}: not a flow, hand_flow or "
                f"knob stimulus; {fix}"
            )
        if want is not None and kind is not None and kind != want:
            raise UserError(f"{where}: {pre}stimulus is a {kind} stimulus in a {want} plan; {fix}")
        if kind is not None:
            check_record(t["stimulus"], STIMULUS[kind], where, fix, prefix=pre + "stimulus.")
        if run and kind != "knob" and t.get("direction") not in plan["responses"]:
            raise UserError(
                f"{where}: {pre}direction = {_show(t.get('direction'))}: not one of the plan's "
                f"responses {plan['responses']}; {fix}"
            )
    _check_factors(plan.get("factors", {}), where, fix)
    seen: set[int] = set()
    for i, q in enumerate(plan.get("questionnaires", [])):
        pre = f"questionnaires[{i}]."
        check_record(q, QUESTIONNAIRE, where, fix, prefix=pre)
        if not 0 <= q["after_trial"] < len(trials) or q["after_trial"] in seen:
            raise UserError(
                f"{where}: {pre}after_trial = {q['after_trial']}: must be a trial of the plan "
                f"(0..{len(trials) - 1}), once; {fix}"
            )
        seen.add(q["after_trial"])
        for j, item in enumerate(q["items"]):
            check_record(item, ITEM, where, fix, prefix=f"{pre}items[{j}].")
    return plan


def _check_factors(factors: dict[str, Any], where: str, fix: str) -> None:
    """``factors``: each phase's factors, each a list of levels (names or numbers)."""
    level = Key("scalar")
    for phase, table in factors.items():
        if not isinstance(table, dict):
            raise UserError(f"{where}: factors.{phase} = {_show(table)}: must be an object; {fix}")
        for name, levels in table.items():
            if not isinstance(levels, list) or not all(level.ok(v) for v in levels):
                raise UserError(
                    f"{where}: factors.{phase}.{name} = {_show(levels)}: must be a list of "
                    f"levels (names or numbers); {fix}"
                )


def load_plan(path: Path, words: Words = CLI, *, run: bool = False) -> dict[str, Any]:
    """``plan.json`` read and checked (``run``: for a resume)."""
    fix = _fix(words)
    plan = textfiles.read_json(path, what="study plan (plan.json)", fix=fix)
    return check_plan(plan, str(path), fix, run=run)


def load_participant(
    path: Path, words: Words = CLI, *, pid: str | None = None
) -> dict[str, Any] | None:
    """``participant.json`` read and checked (None when there is none); ``pid``: the
    participant this folder is for."""
    p = Path(path)
    if not p.exists() and not p.is_symlink():
        return None
    fix = _fix(words)
    rec = textfiles.read_json(p, what="participant record (participant.json)", fix=fix)
    check_record(rec, PARTICIPANT, str(p), fix)
    if pid is not None and rec["id"] != pid:
        raise UserError(f"{p}: id = {_show(rec['id'])} but this folder is {pid}'s; {fix}")
    return rec


# ----------------------------------------------------------------- trials.jsonl
COMMON = {
    "event": _str(need="all", choices=EVENTS),
    "participant": _str(need="all"),
    "experiment": _str(need="all"),
}
EVENT = {
    "start": {"trial": _int(need="all"), "phase": _str(), "t_start": _num()},
    "interrupted": {"trial": _int(need="all"), "reason": _str(null=True), "t": _num()},
    "done": {
        "trial": _int(need="all"),
        "phase": _str(need="all"),
        "correct": Key("bool", need="all"),
        "response": _str(null=True),
        "replays": _int(),
        "response_time_s": _num(0, null=True),
        "simulated": Key("bool"),
        "t_start": _num(),
        "t_end": _num(),
        "stimulus": Key("dict"),
        "block": Key("scalar", null=True),
        **{k: _str(null=True) for k in TRIAL_COLUMNS[2:]},
        "completion_time_s": _num(0, null=True),
        "overshoots": _int(),
        "recovery_time_s": _num(0, null=True),
        "timed_out": Key("bool"),
        "error": _str(),
        "sectors": _int(2),
        "distance_deg": _num(0),
        "start_item": _int(null=True),
        "target_item": _int(null=True),
        "detents": _int(null=True),
    },
    "questionnaire": {
        "after_trial": _int(need="all"),
        "condition": Key("scalar", null=True),
        "category": _str(need="all"),
        "item": _int(1, need="all"),
        "text": _str(),
        "score": _int(1, 11, need="all"),
        "t": _num(),
    },
}
