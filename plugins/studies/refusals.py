"""The Studies screen's refusals, one rule (issue 27): a refusal is about what it was said
of, the screen's fields and the run as they were, and leaves the status when they change
(a field typed in, another participant, a run started or stopped), or, when it names a
run holding the outputs (a shell's ``haptable study run``), when that run lets them go;
what is true then shows in its place (the choice's saved progress).

A start refused before its run began (``Stopped`` with ``refused: ...``: another run
holds the outputs, the participant's folder ...) changes nothing of what the screen
showed of the participant: the saved progress, the bar and the trials stay until the
run's first report (``begin`` / ``run_began`` / ``refused``)."""

from __future__ import annotations

from collections.abc import Callable
from typing import Any

from textual.widgets import Checkbox, Input, ProgressBar, Select

from console.plugin_api.tui import lapse, outputs_held

from .panel_choice import show_choice
from .trials_table import TrialsTable


def form(pane: Any) -> tuple:
    """What a refusal is about: every field's value and the run going on (or none)."""
    fields = pane.query("Input, Select, Checkbox")
    values = tuple((w.id, w.value) for w in fields if isinstance(w, Input | Select | Checkbox))
    return (*values, pane.running)


def tie(
    pane: Any,
    text: str,
    about: Callable[[], object] | None = None,
    shown: Callable[[], str] | None = None,
) -> None:
    """The status's refusal ``text`` (``pane.said``, or what ``shown()`` reads) lapses
    once ``about()`` (default: the ``form``) is not what it was, or the run it names as
    holding the outputs let them go; the choice's progress as the folder holds it then
    shows in its place."""
    state = about or (lambda: form(pane))
    line = shown or (lambda: pane.said[0])
    was = state()
    session = pane.app.session
    held = "holds the outputs" in text  # said until the hold ends (as Relays' line)

    def still() -> bool:
        return state() == was and (not held or outputs_held(session))

    def gone(_then: str) -> None:
        if shown is None:
            pane.said = ("", "information")
        else:  # a refused start's line (``refused``)
            pane.last.pop("stopped", None)
            pane.last.pop("error", None)
        if pane.running is None:
            show_choice(pane)  # what the folder holds now (the other run wrote to it)
        else:
            pane._status(pane._status_text)

    lapse(pane, line, text, gone, while_true=still)


def begin(pane: Any, pid: str) -> None:
    """``s`` starts ``pid``'s run: the participant's saved count kept (the head says it
    while the run prepares); the bar and the trials stay until the run reports."""
    kept = pane.last if pane.last.get("pid") == pid else {}
    pane.last = {k: kept[k] for k in ("pid", "done", "total") if k in kept} | {"pid": pid}
    pane.run_began = False


def run_began(pane: Any) -> None:
    """The run's first report (its map, its earlier trials, its start): the bar and the
    trials table are the run's from now on."""
    if getattr(pane, "run_began", True):
        return
    pane.run_began = True
    pane.query_one("#study-trials", TrialsTable).clear_trials()
    pane.query_one("#study-progress", ProgressBar).update(total=1, progress=0)


def refused(pane: Any, pid: str, reason: str) -> None:
    """The run of ``pid`` stopped before it began (``reason``: ``refused: ...``): the
    choice's saved progress as the folder holds it, and the refusal under it, tied to
    its cause (``tie``)."""
    pane.run_out = pane.run_study = None  # nothing ran: nothing to analyse again
    show_choice(pane)  # the saved progress as it is (its count in the head)
    # the status's last line, in red (``status_lines``); logged as the run's failure
    pane.last = {**pane.last, "pid": pid, "stopped": reason, "error": reason}
    pane._show()
    tie(pane, reason, shown=lambda: pane.last.get("stopped", ""))
