"""The files of a run (``--out DIR``): what the runner writes and resumes from.

``DIR/<participant>/participant.json`` (id, age, sex, handedness, hand_width_cm,
hand_length_cm, consent_noted, consent_time, simulated, observer), ``plan.json`` (written
atomically before the first trial) and ``trials.jsonl`` (one JSON object per line,
appended and fsynced per event; the columns are in this package's README.md). A
``start`` without its ``done`` is a trial in flight at a crash: ``open_run`` marks it
``interrupted`` and the run repeats it; the run continues at the first trial of the stored
plan without a ``done``.
"""

from __future__ import annotations

import json
import math
import re
import time
from dataclasses import asdict, dataclass, field
from pathlib import Path
from typing import Any

from console.plugin_api import UserError, append_json_line, write_text_atomic

from . import records
from .events import load_events, read_events
from .records import HANDEDNESS, SEXES
from .words import CLI, Words, listing

__all__ = ["HANDEDNESS", "SEXES", "read_events"]
_ID = re.compile(r"[A-Za-z0-9][A-Za-z0-9_.-]{0,63}")


@dataclass(frozen=True)
class Participant:
    id: str
    age: int
    sex: str
    handedness: str
    hand_width_cm: float
    hand_length_cm: float
    consent_noted: bool
    consent_time: str = ""
    simulated: bool = False
    observer: dict[str, Any] = field(default_factory=dict)


def check_id(pid: str) -> str:
    """``pid`` as a participant's folder name, else one line with the rule it breaks:
    the characters, the first one (``.``, ``..`` and ``-x`` name no folder of their own
    or read as an option) or the length."""
    if isinstance(pid, str) and _ID.fullmatch(pid):
        return pid
    text = pid if isinstance(pid, str) else ""
    if len(text) > 64:
        why = f"at most 64 characters (it has {len(text)})"
    elif text and re.fullmatch(r"[A-Za-z0-9_.-]+", text):
        why = (
            f"start with a letter or digit, not {text[0]!r} ('.' and '..' name no folder "
            "of their own; e.g. P01)"
        )
    else:
        why = "use letters, digits, '_', '-' or '.' (e.g. P01), starting with a letter or digit"
    raise UserError(f"participant {pid!r}: {why}")


#: a participant's number fields: (lowest, highest)
DETAIL_RANGES = {"age": (1, 120), "hand_width_cm": (3, 30), "hand_length_cm": (5, 40)}


def check_detail(pid: str, name: str, v: Any, words: Words = CLI) -> Any:
    """One of the participant's details (``age``, ``sex``, ``handedness``,
    ``hand_width_cm``, ``hand_length_cm``) as stored, or one line naming the field (as
    ``words`` calls it) and the rule (``UserError``): the check of ``make_participant``,
    also for each answer typed at a prompt."""
    label = words.fields.get(name, name)
    shown = f"{label} {v}" if label.startswith("--") else f"{label} = {v!r}"
    if name in ("sex", "handedness"):
        options = SEXES if name == "sex" else HANDEDNESS
        k = str(v).strip().lower()
        hits = [o for o in options if o == k] or [o for o in options if o.startswith(k)]
        if len(hits) != 1:
            raise UserError(f"participant {pid}: {shown}: use one of {', '.join(options)}")
        return hits[0]
    lo, hi = DETAIL_RANGES[name]
    try:
        x = float(v)
    except (TypeError, ValueError):
        x = math.nan
    if not (math.isfinite(x) and lo <= x <= hi):
        raise UserError(f"participant {pid}: {shown}: give a number from {lo:g} to {hi:g}")
    if name != "age":
        return x
    if x != int(x):
        raise UserError(f"participant {pid}: {shown}: give whole years")
    return int(x)


def make_participant(
    pid: str,
    *,
    age: Any,
    sex: Any,
    handedness: Any,
    hand_width_cm: Any,
    hand_length_cm: Any,
    consent: Any,
    simulated: bool = False,
    observer: dict[str, Any] | None = None,
    words: Words = CLI,
) -> Participant:
    """A checked participant: the missing fields named at once, else each bad value in
    one line naming the field (as ``words`` calls it) and the fix. ``sex`` and
    ``handedness`` are taken in any case and by a unique start (``F``: female)."""
    check_id(pid)

    given = {"age": age, "sex": sex, "handedness": handedness}
    given |= {"hand_width_cm": hand_width_cm, "hand_length_cm": hand_length_cm}
    missing = [name for name, v in given.items() if v is None or str(v).strip() == ""]
    if missing:
        names = [words.fields.get(k, k) for k in missing]
        also = f" and note the consent ({words.consent})" if consent is not True else ""
        raise UserError(
            f"participant {pid}: {listing(names)} missing; give "
            f"{'it' if len(names) == 1 else 'them'}{also} before the first trial"
        )

    age = check_detail(pid, "age", age, words)
    sex = check_detail(pid, "sex", sex, words)
    handedness = check_detail(pid, "handedness", handedness, words)
    w = check_detail(pid, "hand_width_cm", hand_width_cm, words)
    length = check_detail(pid, "hand_length_cm", hand_length_cm, words)
    if consent is not True:
        raise UserError(
            f"participant {pid}: consent not noted; note the participant's informed consent "
            f"({words.consent}) before the first trial"
        )
    return Participant(
        pid,
        age,
        sex,
        handedness,
        w,
        length,
        True,
        time.strftime("%Y-%m-%dT%H:%M:%SZ", time.gmtime()),
        bool(simulated),
        dict(observer or {}),
    )


# ------------------------------------------------------------------ durable writes
def write_json_atomic(path: Path, obj: Any) -> None:
    """Write ``obj`` as JSON so that ``path`` holds the old or the new file, never half."""
    write_text_atomic(Path(path), json.dumps(obj, indent=1, sort_keys=True) + "\n")


# ------------------------------------------------------------------ a participant's run
@dataclass
class RunFiles:
    """One participant's folder: ``participant.json``, ``plan.json``, ``trials.jsonl``;
    ``plan``: the checked plan its events are checked against (``open_run`` sets it)."""

    root: Path
    plan: dict[str, Any] | None = None

    @property
    def participant_path(self) -> Path:
        return self.root / "participant.json"

    @property
    def plan_path(self) -> Path:
        return self.root / "plan.json"

    @property
    def trials_path(self) -> Path:
        return self.root / "trials.jsonl"

    def events(self) -> list[dict[str, Any]]:
        """The events, checked against the plan (``records``) once it is known."""
        if self.plan is None:
            return read_events(self.trials_path)
        return load_events(self.trials_path, self.plan)

    def append(self, record: dict[str, Any]) -> None:
        append_json_line(self.trials_path, record)


def participant_dir(out: Path, pid: str) -> Path:
    return Path(out).expanduser() / check_id(pid)


def load_participant(files: RunFiles, words: Words = CLI) -> dict[str, Any] | None:
    """The stored participant (checked: ``records.PARTICIPANT``), None when there is none."""
    return records.load_participant(files.participant_path, words, pid=files.root.name)


def save_participant(files: RunFiles, p: Participant) -> None:
    write_json_atomic(files.participant_path, asdict(p))


@dataclass(frozen=True)
class Progress:
    """Where a run stands: trials ``done`` (indices), the trial ``in_flight`` at a crash
    (or None), ``next_trial`` (None: all done) and the questionnaires answered (by the
    trial they follow)."""

    done: frozenset[int]
    in_flight: int | None
    next_trial: int | None
    questionnaires_done: frozenset[int]
    total: int


def progress(plan: dict[str, Any], events: list[dict[str, Any]]) -> Progress:
    done: set[int] = set()
    open_start: int | None = None
    answered: dict[int, set[tuple[str, int]]] = {}
    q_after = {q["after_trial"]: q for q in plan.get("questionnaires", [])}
    for e in events:
        ev, i = e.get("event"), e.get("trial")
        if ev == "start":
            open_start = i
        elif ev in ("done", "interrupted"):
            if ev == "done":
                done.add(int(i))
            if open_start == i:
                open_start = None
        elif ev == "questionnaire":
            answered.setdefault(int(e.get("after_trial", -1)), set()).add(
                (e.get("category"), e.get("item"))
            )
    n = len(plan["trials"])
    nxt = next((t["index"] for t in plan["trials"] if t["index"] not in done), None)
    q_done = frozenset(k for k, q in q_after.items() if len(answered.get(k, ())) >= len(q["items"]))
    return Progress(frozenset(done), open_start, nxt, q_done, n)


def resume_text(plan: dict[str, Any], events: list[dict[str, Any]]) -> str | None:
    """Where a run resumes, for one line ("resuming at trial 5 of 200 (4 done; trial 5 was
    interrupted and runs again)"); None for a run not started yet or finished."""
    st = progress(plan, events)
    if st.next_trial is None or not (st.done or events):
        return None
    n = st.next_trial
    cut = any(e.get("event") == "interrupted" and e.get("trial") == n for e in events)
    why = f"; trial {n + 1} was interrupted and runs again" if cut else ""
    return f"resuming at trial {n + 1} of {st.total} ({len(st.done)} done{why})"


#: what a stored plan must share with the plan this run would make to be resumed by it
SAME = ("experiment", "protocol_sha256", "participant", "stimulus", "responses", "seed")
#: how a resume fixes each difference
HOW = {
    **dict.fromkeys(
        ("experiment", "protocol_sha256", "stimulus", "responses"),
        "resume with the same protocol file",
    ),
    "participant": "restore it (it is another participant's plan)",
    "seed": "resume it as it was started (the same --seed and --row)",
}


def _cells(plan: dict[str, Any]) -> list[str]:
    """The plan's trials as a sorted list (their order may come from another numpy) and
    its questionnaires."""
    keys = [k for k in records.TRIAL if k != "index"]
    rows = [json.dumps([t.get(k) for k in keys], sort_keys=True) for t in plan["trials"]]
    qkeys = list(records.QUESTIONNAIRE)
    qs = [
        json.dumps([q.get(k) for k in qkeys], sort_keys=True)
        for q in plan.get("questionnaires", [])
    ]
    return sorted(rows) + qs


def resumable(
    stored: dict[str, Any], plan: dict[str, Any], path: Path, words: Words = CLI
) -> dict[str, Any]:
    """The stored plan (``path``, read by ``records.load_plan(..., run=True)``) when it is
    the plan this run would make (the same protocol, participant, seed and row; the same
    trials, in its own order); else one line naming the first difference."""
    for key in (*SAME, "latin_square_row"):
        if stored.get(key) != plan.get(key):
            raise UserError(
                f"{path}: {key} = {stored.get(key)!r} but this run has {plan.get(key)!r}; "
                f"{HOW.get(key, HOW['seed'])} or use a new {words.out}"
            )
    if _cells(stored) != _cells(plan):
        raise UserError(
            f"{path}: its trials or questionnaires are not those of this protocol and seed "
            f"(the file was edited); restore it or start a new {words.out}"
        )
    return stored


def open_run(
    out: Path, pid: str, plan: dict[str, Any], words: Words = CLI
) -> tuple[RunFiles, dict[str, Any]]:
    """The participant's folder ready to run: a new plan stored (atomically) before any
    trial, or the stored one when its protocol and seed agree (a resume; a trial in flight
    at a crash is marked ``interrupted``). Returns the files and the plan to follow."""
    files = RunFiles(participant_dir(out, pid))
    try:
        files.root.mkdir(parents=True, exist_ok=True)
    except OSError as exc:
        raise UserError(
            f"{files.root}: cannot make the participant's folder ({exc.strerror or exc}); "
            f"give a writable {words.out}"
        ) from None
    if files.plan_path.exists() or files.plan_path.is_symlink():
        stored = records.load_plan(files.plan_path, words, run=True)
        plan = resumable(stored, plan, files.plan_path, words)
    else:
        write_json_atomic(files.plan_path, plan)
    files.plan = plan
    st = progress(plan, files.events())
    if st.in_flight is not None:
        files.append(
            {
                "event": "interrupted",
                "trial": st.in_flight,
                "participant": pid,
                "experiment": plan["experiment"],
                "t": time.time(),
            }
        )
    return files, plan
