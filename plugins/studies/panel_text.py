"""What the Studies screen says and works out beside its widgets: its help, a protocol's default results
folder, the next participant's id, a trial in words, a text clipped to a column, the
status block of a run."""

from __future__ import annotations

import re
from pathlib import Path
from typing import Any

from console.plugin_api import data_dir
from console.plugin_api.tui import NumberField, cut_chars, escape

#: the Studies screen's help (``?``): plain text, keys first (``console.tui.help``)
HELP = (
    "Pick the protocol, the participant and the folder; a person needs age,\n"
    "sex, handedness, hand size and the consent noted (a simulated one not).\n"
    "s / Start     start (or resume: the same participant continues where it\n"
    "              stopped); refused during an e-stop (ctrl+r resets it); a run\n"
    "              over 5 min says its size and time first: s again starts it\n"
    "p             pause after this trial / resume\n"
    "r             replay the stimulus (within the phase's replays)\n"
    "a             abort: a again within 3 s (the trial in flight is repeated\n"
    "              on resume)\n"
    "n / Analyse   analyse the folder's runs of this protocol: the report\n"
    "              (<folder>/<protocol>-report.html) and the ANOVA table\n"
    "t             show the trials / the analysis\n"
    "[ / ]         an adaptive run's plot: previous / next track (t: the plot in\n"
    "              the analysis's place); + correct, x wrong, ◆ reversal\n"
    "o             the analysis's notes: all of them / one line\n"
    "arrows        answer up/down/left/right (a keypad: 8 2 4 6); 1 / 2:\n"
    "              left to right / right to left (experiment 1)\n"
    "1..7          a questionnaire score (up to 9 on a protocol's longer\n"
    "              scale); an adaptive trial: the interval (1..3)\n"
    "enter         in a text field: the next one (the footer names the field)\n"
    "escape        leave a text field (what was typed stays)\n"
    "A flow study (exp1, exp2) plays on the console's vibration map: with\n"
    "none loaded or kept, s measures the twin's grid first."
)


def default_out(study: str = "") -> Path:
    """A protocol's default results folder: ``<data dir>/studies/<protocol>``."""
    return data_dir("studies", study) if study else data_dir("studies")


def next_id(pid: str) -> str:
    """The next participant's id (``P01`` -> ``P02``; an id without a number: itself)."""
    m = re.match(r"^(.*?)(\d+)$", pid)
    if not m:
        return pid
    return f"{m.group(1)}{int(m.group(2)) + 1:0{len(m.group(2))}d}"


def trial_text(t: dict[str, Any]) -> str:
    """A trial as the experimenter reads it: phase, place, direction or condition."""
    place = t.get("region") or (f"pair {t['pair']}" if t.get("pair") else "")
    what = t.get("direction") or t.get("condition") or ""
    if t.get("stimulus", {}).get("task") == "knob":
        s = t["stimulus"]
        what = f"{s['condition']} {s['sectors']} sectors {s['distance_deg']:g} deg"
    hand = f" ({t['hand']} hand)" if t.get("hand") else ""
    return " ".join(x for x in (t.get("phase", ""), place, what) if x) + hand


def clip(text: str, width: int) -> str:
    """``text`` within ``width`` columns, ending in ``…`` when cut, never inside a
    bracket it would leave open (``(right hand`` goes whole)."""
    return cut_chars(text, width)


def same_folder(a: Path, b: Path) -> bool:
    """The same folder (as typed, or resolved)."""
    try:
        return Path(a).expanduser().resolve() == Path(b).expanduser().resolve()
    except OSError:
        return Path(a) == Path(b)


#: the participant's number fields: (label, lowest, highest, whole numbers only)
NUMBER_FIELDS = {
    "age": ("age", 1, 120, True),
    "hand_width_cm": ("hand width cm", 3, 30, False),
    "hand_length_cm": ("hand length cm", 5, 40, False),
}


def number_field(field: str) -> NumberField:
    """The participant's number ``field``: it takes the range its check reads
    (``NUMBER_FIELDS``), its longest number shown whole."""
    _, lo, hi, whole = NUMBER_FIELDS[field]
    return NumberField(id=field, lo=lo, hi=hi, whole=whole, compact=True)


def field_refusal(field: str, value: str) -> str:
    """Why ``value`` in the participant's number ``field`` is refused ('' when it is
    empty or fits), one line naming the field and what it takes."""
    if field not in NUMBER_FIELDS or not value.strip():
        return ""
    label, lo, hi, whole = NUMBER_FIELDS[field]
    try:
        x = float(value)
    except ValueError:
        x = float("nan")
    if not lo <= x <= hi or (whole and x != int(x)):
        what = "whole years" if whole else "a number"
        return f"{label} = {value.strip()!r}: give {what} from {lo} to {hi}"
    return ""


def status_lines(
    last: dict[str, Any],
    running: str | None,
    paused: bool,
    abort_within_s: float | None,
    aborting: bool = False,
) -> list[str]:
    """The Studies status block (markup) for the run's ``last`` state: who and how far,
    the trial, the runner's state, the abort question (``abort_within_s``: a second
    ``a`` within that many seconds aborts) or the abort asked for (``aborting``, until
    the run stopped), or how the run ended."""
    L = last
    who = running or L.get("pid") or "-"  # the participant also once stopped
    if "total" in L:
        done = f"{escape(L['done'])}/{escape(L['total'])} trials done"
        if running and L.get("left"):  # at the pace so far (panel_status)
            done += f", {escape(L['left'])}"
    else:  # no plan reached yet (a refused start): no count to show
        done = "not started" if not running else "preparing"
    head = f"[b]{escape(who)}[/b]: " + done  # done: escaped above
    if paused:
        stopped_there = L.get("state", "").startswith("paused")  # the runner stopped there
        head += "  [yellow]paused[/]" if stopped_there else "  [yellow]pausing after this trial[/]"
    lines = [head]
    if L.get("trial") and running:
        t = L["trial"]
        which = "next: trial" if L.get("next") else "trial"
        lines.append(f"{which} {t['index'] + 1}: {escape(trial_text(t))}")
    if L.get("state") and running:
        lines.append(escape(L["state"]))
    if running and aborting:
        lines.append(
            f"[b]aborting {escape(running)}'s run[/b] (the trial in flight stops; it runs "
            "again on resume)"
        )
    elif running and abort_within_s is not None:
        lines.append(
            f"[b]a again within {abort_within_s:g} s aborts {escape(running)}'s run[/b] "
            "(the trial in flight runs again on resume)"
        )
    if not running and L.get("reset"):  # the e-stop that stopped it is reset
        lines.append(escape(L["reset"]))
    elif not running and L.get("stopped"):
        error = L.get("error")
        refused = L["stopped"].startswith("refused: ") or "total" not in L  # not run
        ended = f"{who}'s run {'refused' if refused else 'stopped'}"  # whose, on the line
        if error and error == L["stopped"]:  # a failure: its reason once, in red
            why = error.removeprefix("refused: ")
            lines.append(f"[red]{escape(ended)}: {escape(why)}[/]")
        else:
            lines.append(f"{escape(ended)}: {escape(L['stopped'])}")
            if error:
                lines.append(f"[red]{escape(error)}[/]")
    return lines


def space_held(tick_words: str) -> str:
    """What a space held by a check box says (``Tick.SpaceHeld``): where the focus is."""
    return (
        f"space not taken: the focus is on the '{tick_words}' check box, not a text field "
        "(Tab moves to the next field; space alone ticks it)"
    )
