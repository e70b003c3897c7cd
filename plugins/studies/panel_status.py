"""What the Studies screen's status says as a run goes on, kept true (issue 27): the
experimenter's last key's outcome lasts until the run's state moves on (a trial starts,
the pause takes hold, the run ends) or another key speaks; the count of trials done
says the time left at the pace since the run (re)started; a run that stopped is
analysed at once, so ``t`` shows it without ``n`` first."""

from __future__ import annotations

import time
from typing import Any

from console.plugin_api import UserError
from console.plugin_api.tui import Pace, left_words, seconds_left

from . import adaptive_console
from . import protocol as protocols
from .panel_text import NUMBER_FIELDS, same_folder, trial_text

#: the run's snapshots after which the experimenter's last key's outcome is past
STATE_KINDS = frozenset({"start", "paused", "aborted", "finished", "questionnaire", "rate"})


def said_lapses(said: tuple[str, str], kind: str) -> bool:
    """Whether a snapshot ``kind`` makes the key's outcome ``said`` past: the run's
    state moved on (an error stays until the next key; a field's refusal stays until
    the field is right)."""
    text, severity = said
    if not text or severity == "error" or kind not in STATE_KINDS:
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


def map_state(last: dict[str, Any], d: dict[str, Any], clock=time.monotonic) -> str:
    """The status line of the run's vibration-map step (a ``map`` snapshot: its text and
    the fraction done) with the time it still needs at its pace so far, as the other long
    steps say it ("about 8 s left"); its clock starts when the step reports no progress
    yet (the measurement's start)."""
    fraction, now = float(d.get("fraction") or 0.0), clock()
    if fraction <= 0.0 or last.get("map_t0") is None:
        last["map_t0"] = now
    left = "" if fraction >= 1.0 else left_words(seconds_left(now - last["map_t0"], fraction))
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
