"""What the Studies screen's status says as a run goes on, kept true (issue 27): the
experimenter's last key's outcome lasts until the run's state moves on (a trial starts,
the pause takes hold, the run ends), not before it held the line for ``ANSWER_HOLD_S``,
or another key speaks; the count of trials done
says the time left at the pace since the run (re)started; a run that stopped is
analysed at once, so ``t`` shows it without ``n`` first."""

from __future__ import annotations

import time
from pathlib import Path
from typing import Any

from textual.widgets import DataTable, Static

from console.plugin_api import JobLeft, UserError
from console.plugin_api.tui import Pace, left_words

from . import adaptive_console
from . import protocol as protocols
from .panel_text import NUMBER_FIELDS, same_folder, trial_text

#: the run's snapshots after which the experimenter's last key's outcome is past
STATE_KINDS = frozenset({"start", "paused", "aborted", "finished", "questionnaire", "rate"})


#: seconds a key's outcome holds the status line at least: a simulated run's next trial
#: starts within milliseconds, and its progress took ``r``'s answer before anyone read it
ANSWER_HOLD_S = 5.0


def said_lapses(said: tuple[str, str], kind: str, age_s: float) -> bool:
    """Whether a snapshot ``kind`` makes the key's outcome ``said`` (said ``age_s`` ago)
    past: the run's state moved on once it has held the line ``ANSWER_HOLD_S`` (an
    error stays until the next key; a field's refusal stays until the field is right)."""
    text, severity = said
    if not text or severity == "error" or kind not in STATE_KINDS or age_s < ANSWER_HOLD_S:
        return False
    return not any(text.startswith(f"{label} = ") for label, *_ in NUMBER_FIELDS.values())


def pace_snapshot(pace: Pace, last: dict[str, Any], kind: str, d: dict[str, Any]) -> None:
    """Keep ``last["left"]`` (the time left in words) from the run's snapshots: a trial
    starting after a pause starts the pace again (the wait is not work)."""
    if kind == "paused":
        pace.stop()
        last["left"] = ""
    elif kind == "start" and pace.t0 is None and "done" in last:
        pace.start(int(last["done"]))
    elif kind == "progress":
        done, total = int(d["done"]), int(d["total"])
        last["left"] = "" if done >= total else left_words(pace.left(done, total))
    elif kind in ("aborted", "finished"):
        pace.stop()
        last["left"] = ""


#: words of a line saying the e-stop is active (stale once the operator reset it)
ESTOP_ACTIVE = ("e-stop active", "e-stop is active", "e-stop latched", "ctrl+r resets")


def estop_reset(last: dict[str, Any], reset: bool) -> bool:
    """Keep ``last["reset"]`` (the line said in place of how the run stopped) true: the
    operator's reset (``reset``) of an e-stop that stopped the run says it and where ``s``
    goes on; a new e-stop takes it away (the stop's own line, saying ctrl+r resets, shows
    again). Returns whether the status changed."""
    if not reset:
        return last.pop("reset", None) is not None
    said = f"{last.get('stopped', '')} {last.get('error', '')}"
    if not any(w in said for w in ESTOP_ACTIVE):
        return False
    who = last.get("pid") or "the participant"
    if "total" in last and int(last["done"]) < int(last["total"]):
        goes_on = f"s resumes {who} at trial {int(last['done']) + 1} of {last['total']}"
    else:
        goes_on = f"s starts {who}'s run"
    last["reset"] = f"e-stop reset: {goes_on}"
    return True


def map_state(last: dict[str, Any], d: dict[str, Any], clock=time.monotonic) -> str:
    """The status line of the run's vibration-map step (a ``map`` snapshot: its text and
    the fraction done) with the time it still needs at its pace so far, as the other long
    steps say it ("about 8 s left"); its clock starts when the step reports no progress
    yet (the measurement's start)."""
    fraction = float(d.get("fraction") or 0.0)
    if fraction <= 0.0 or last.get("map_job") is None:
        last["map_job"] = JobLeft(clock=clock)  # the console's one rule: steady
    job: JobLeft = last["map_job"]
    report = fraction != last.get("map_fraction")  # else a poll: the clock only
    last["map_fraction"] = fraction
    left = "" if fraction >= 1.0 else job.words(fraction if report else None)
    text = f"vibration map: {d.get('text', '')}"
    return f"{text}, {left}" if left else text


def analyse_after_run(pane: Any, pid: str) -> None:
    """A run stopped: its folder analysed now, the view left as it is (``t`` shows the
    analysis at once); an adaptive protocol has its plot instead."""
    out, study = pane.run_out, pane.run_study
    pane.run_out = pane.run_study = None
    if out is None or not study or adaptive_console.is_adaptive(study):
        return
    try:
        experiment = protocols.load(study).name
    except UserError:
        return  # the protocol's own refusal is said where it is used
    again = pane.analysed is not None and same_folder(pane.analysed[0], out)
    why = f"{' again' if again else ''} after {pid}'s run"
    pane._start_analysis(out, experiment, why=why, show=False)


def trial_row(r: dict[str, Any]) -> tuple[str, ...]:
    """A done trial's row of the trials table: number, what, response, correct,
    replays, response time."""
    rt = r.get("response_time_s")
    if r.get("completion_time_s") is not None or "overshoots" in r:
        ct = r.get("completion_time_s")
        resp = f"{'timeout' if ct is None else f'{ct:.2f} s'} {r.get('overshoots')} ovs"
    else:
        resp = str(r.get("response"))
    return (
        str(r["trial"] + 1),
        trial_text(r),
        resp,
        "yes" if r.get("correct") else "no",
        str(r.get("replays", 0)),
        "-" if rt is None else f"{rt:.2f} s",
    )


def show_analysis(pane: Any, d: dict[str, Any]) -> None:
    """An analysis came in (a ``Snapshot`` of kind ``analysis``): its title, the ANOVA
    table, the notes and the report's path; the same analysis again leaves it as it is
    (``o``'s choice kept)."""
    pane.query_one("#analysis-head", Static).update(d["title"])
    shown, pane._shown = pane._shown, (d["title"], repr(d["rows"]), tuple(d["notes"]))
    pane._busy = False
    if shown == pane._shown:  # the same analysis again (after a run and n): as it is
        if pane._show_result:
            pane._view("analysis")
        return
    table = pane.query_one("#study-anova", DataTable)
    table.clear(columns=True)
    table.add_columns(*d["columns"])
    for row in d["rows"]:
        table.add_row(*row)
    pane.notes = list(d["notes"])
    if not d["rows"]:
        pane.notes.insert(0, "no ANOVA table: the notes say why")
    pane._notes(open_=not d["rows"])  # without a table the notes take its place
    report = Path(d["report"])
    out = pane.analysed[0] if pane.analysed else None
    where = f"{report.name} in the folder" if out and same_folder(report.parent, out) else report
    pane.query_one("#analysis-report", Static).update(f"report: {where}")
    if pane._show_result:
        pane._view("analysis")


def analysis_failed(pane: Any, message: str) -> None:
    """The analysis failed: its line alone, nothing of an earlier analysis under it."""
    pane.query_one("#analysis-head", Static).update(message)
    pane.query_one("#study-anova", DataTable).clear(columns=True)
    pane.notes, pane._shown, pane._busy = [], (), False
    pane._notes(open_=False)
    pane.query_one("#analysis-report", Static).update("")
    if pane._show_result:
        pane._view("analysis")
