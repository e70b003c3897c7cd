"""The Studies screen's choice (protocol, participant, folder) shown as what it is now:
when one of them changes (no run going on) the progress bar, the status and the trials
table show that participant's saved run of that protocol in that folder, or nothing yet
(never the previous choice's); and ``s`` asks first before a long run (``saved_run``)."""

from __future__ import annotations

import re
from pathlib import Path
from typing import Any

from textual.widgets import Input, ProgressBar, Select

from console.plugin_api import UserError
from console.plugin_api.tui import AskAgain
from console.plugin_api.tui import chosen as text_of

from . import adaptive_console
from .adaptive_view import AdaptiveView
from .panel_fit import protocol_changed
from .panel_status import trial_row
from .panel_text import default_out
from .saved_run import run_size, saved, stimulus_seconds
from .store import check_id
from .trials_table import TrialsTable

#: how the line refusing a folder that is a file begins
FILE_SAID = "folder:"

#: seconds within which a second ``s`` starts a long run
LONG_AGAIN_S = 5.0


def chosen(pane: Any) -> tuple[str, str, Path] | None:
    """(protocol, participant, folder) as the fields hold them; None without a protocol."""
    study = text_of(pane.query_one("#protocol", Select).value)
    if not study:
        return None
    pid = pane.query_one("#participant", Input).value.strip()
    out = pane.query_one("#out", Input).value.strip()
    return str(study), pid, Path(out or default_out(str(study))).expanduser()


def show_choice(pane: Any) -> None:
    """The chosen participant's saved run of the chosen protocol in the progress bar,
    the status and the trials table, or nothing yet (the idle status), unless a run is
    going on."""
    choice = chosen(pane)
    if pane.running is not None or choice is None:
        return
    study, pid, out = choice
    run = saved(out, pid, study)
    pane.last = {"pid": pid, "done": run.done, "total": run.total} if run else {}
    bar = pane.query_one("#study-progress", ProgressBar)
    bar.update(total=max(run.total, 1) if run else 1, progress=run.done if run else 0)
    table = pane.query_one("#study-trials", TrialsTable)
    table.clear_trials()
    adaptive = adaptive_console.is_adaptive(study)
    for r in run.records if run else []:
        try:
            row = trial_row(adaptive_console.done_row(r) if adaptive else r)
        except (KeyError, TypeError, ValueError):
            continue  # a line the run did not write so: starting says why
        table.add_trial(*row)
    pane.pace.stop()
    pane.query_one(AdaptiveView).reset()
    if pane.query_one("#study-plot").display:  # the plot was the previous run's
        pane._view("trials")
    pane._idle()


def shown_again(pane: Any) -> None:
    """The screen shown (again): the choice's saved progress as the folder holds it now
    (a run saved meanwhile by `haptable study run` in a shell, or by another console),
    when it is not what shows; unless a run goes on here."""
    choice = chosen(pane) if pane.is_mounted else None
    if pane.running is not None or choice is None:
        return
    run = saved(choice[2], choice[1], choice[0])
    now = {"pid": choice[1], "done": run.done, "total": run.total} if run else {}
    if now != {k: pane.last.get(k) for k in now} or bool(now) != bool(pane.last):
        said = pane.said[0]
        if not said or said.startswith("protocol ") or " has finished " in said:
            protocol_changed(pane, choice[0])  # the line about the choice, as it is now
        show_choice(pane)


def field_changed(pane: Any) -> None:
    """The participant or the folder typed: the choice shown anew; a line about the
    choice before (naming another participant) goes; a folder that is a file is refused
    as typed (Enter too), before ``s``."""
    if pane.running is not None:
        return
    choice = chosen(pane)
    said = pane.said[0]
    pid = choice[1] if choice else ""
    about_choice = said.startswith("protocol ") or " has finished " in said
    if about_choice and not (pid and re.search(rf"(?<!\w){re.escape(pid)}(?!\w)", said)):
        pane.said = ("", "information")
    was_refused = said.startswith("participant '")
    try:
        check_id(pid) if pid else None
    except UserError as e:  # a name no folder can take: said as typed, s refuses it
        pane.said = (str(e), "warning")
        pane._idle()
        return
    if was_refused or said.startswith(FILE_SAID):
        pane.said = ("", "information")
    out = choice[2] if choice else None
    if out is not None and out.exists() and not out.is_dir():  # said as typed, not at s
        pane.said = (f"{FILE_SAID} {out} is a file, not a folder: type a folder", "warning")
    show_choice(pane)  # a file holds no run: nothing of the folder before stays shown


def asks_first(pane: Any, ask: AskAgain, spec: dict[str, Any]) -> bool:
    """Whether ``s`` asks before starting ``spec``'s run: one longer than
    ``saved_run.LONG_S`` says its size and time, and ``s`` again within
    ``LONG_AGAIN_S`` (the same choice) starts it."""
    try:
        stim_s = stimulus_seconds(spec["study"], pane.app.session.profile)
        size = run_size(spec["study"], spec["out"], spec["pid"], spec["simulate"], stim_s)
    except UserError:
        return False  # the protocol's own refusal is said as the run starts
    what = repr((spec["study"], spec["pid"], str(spec["out"]), spec["simulate"]))
    if not size.long or ask.confirmed(what):
        return False
    does = f"starts {spec['study']} with {spec['pid']}: {size.words()}"
    ask.ask(pane, "s", does, lambda: pane.said[0], pane._say)
    return True
