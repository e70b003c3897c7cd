"""The Vibration screen's command line: a typed command run on the pane."""

from __future__ import annotations

import shlex
from typing import Any

from console.core.errors import UserError
from console.core.suggest import did_you_mean
from console.tui.panes.vibration_words import COMMANDS, KEY_DIRECTIONS, point_word

#: the command line's words (a point id is any number)
NAMES = ("measure", "import", "load", "cancel", "tables", "hand")


def command_meant(word: str) -> str | None:
    """The command a mistyped word meant (``mesure``: ``measure``), or None (a point
    id, or nothing like a command)."""
    return None if word.isdigit() else did_you_mean(word, NAMES)


def run_command(pane: Any, text: str) -> bool:
    """``51`` | ``51 52`` | ``hand 51 right`` | ``measure`` | ``import ...`` | ``load F``
    | ``tables`` | ``cancel`` on the ``VibrationPane`` ``pane``; True when its work runs
    on (it says how it ended)."""
    words = shlex.split(text)
    if not words:
        return False
    head = words[0].lower()
    if head == "measure":
        pane.action_measure(text)
        return True
    if head in ("import", "load") and pane.refuse_replacing(head):
        return False  # said as an error: the text stays on the line
    if head == "import":
        if len(words) < 2:
            raise UserError("import: give EXC=FILE per excitation, e.g. import PA=pa.uff")
        pane._import(words[1:], pane._new_stop("vib-long"), text)
        return True
    if head == "load":
        if len(words) != 2:
            raise UserError(
                f"load: give one vibration map file (.npz), not {len(words) - 1} words; "
                "quote a path with spaces: load '/tmp/my maps/x.npz'"
            )
        pane._load(words[1], pane._new_stop("vib-long"), text)
        return True
    if head == "cancel":
        pane.action_cancel()
    elif head == "tables":
        pane.action_build_tables()
    elif head == "hand":
        if len(words) != 3 or words[2] not in KEY_DIRECTIONS.values():
            raise UserError("hand: write hand POINT left|right|up|down, e.g. hand 51 right")
        pane.action_hand(words[2], point_word(words[1]))
    elif (meant := command_meant(head)) is not None and not head.isdigit():
        raise UserError(f"{words[0]!r}: not a command; did you mean {meant!r}? ({COMMANDS})")
    elif len(words) == 1:
        pane.audition(*point_words(words, pane.cell_of))
    elif len(words) == 2:
        pane.flow(*point_words(words, pane.cell_of))
    else:
        raise UserError(f"{text!r}: not a command; {COMMANDS}")
    return False


def point_words(words: list[str], cell_of: dict) -> list[int]:
    """The point ids typed, or, when a word is no number, one line naming every word
    that is no point: those and a number off the grid alike (``:999 abc`` named only
    ``'abc'``)."""
    bad = [f"{w!r} is no point id" for w in words if not w.lstrip("-").isdigit()]
    nums = [int(w) for w in words if w.lstrip("-").isdigit()]
    if not bad:  # numbers: the pane names one off the grid (``point_problem``)
        return [point_word(w) for w in words]
    bad += [f"point {n} is off the grid" for n in nums if cell_of and n not in cell_of]
    grid = f"the grid has points {min(cell_of)}-{max(cell_of)}" if cell_of else "e.g. 51"
    raise UserError(f"{'; '.join(bad)} ({grid})")
