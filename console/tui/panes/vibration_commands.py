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
            raise UserError("load: give one vibration map file (.npz)")
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
        pane.audition(point_word(words[0]))
    elif len(words) == 2:
        pane.flow(point_word(words[0]), point_word(words[1]))
    else:
        raise UserError(f"{text!r}: not a command; {COMMANDS}")
    return False
