"""The Devices screen's table cells: within their column, a cut text logged whole once
(the log, ctrl+l, has what a cell could not show; Enter on the row says it)."""

from __future__ import annotations

import logging
from collections.abc import Sequence
from typing import Any

from rich.text import Text

from console.tui.shorten import lead
from console.tui.table_fit import NOTE_MIN, clip, fit_cell, fit_lines, need, widths

log = logging.getLogger("console.tui.panes.devices")

#: the widest a table cell gets on this screen (a longer text ends in "…": the whole
#: text is in the log, ctrl+l, and enter on the row says it)
CELL_MAX = 36


def cell(text: str, where: str, width: int = CELL_MAX) -> Text:
    """A table cell within ``width``; a cut text is logged whole (``where`` says
    whose), so the log (ctrl+l) has what the cell could not show."""
    shown = clip(text, width)
    if shown != " ".join(str(text).split()) and (where, text) not in _LOGGED:
        _LOGGED.add((where, text))  # once: listing again does not repeat it
        log.info("%s: %s", where, text)
    return Text(shown)


_LOGGED: set[tuple[str, str]] = set()

#: the lines a device row neither working nor a problem (a skipped self-test) takes at
#: most while the rows whole would push the card in use out of view
ROW_LINES = 2
#: a device row in one of these states stays whole (it says what to do)
PROBLEMS = ("error", "missing")


def cell_lines(text: str, where: str, width: int, lines: int) -> Text:
    """``cell`` in up to ``lines`` lines (``fit_lines``), a cut text logged whole."""
    if lines <= 1:
        return cell(text, where, width)
    shown = fit_lines(text, width, lines)
    if not shown.plain.endswith("…") or (where, text) in _LOGGED:
        return shown
    _LOGGED.add((where, text))
    log.info("%s: %s", where, text)
    return shown


def reason_lines(why: str, width: int) -> int:
    """The lines a row's why takes within ``width`` up to the end of its reason (its
    first clause, ``console.tui.shorten.lead``) and the "…" after it: a shortened row
    gives way to its reason, never cut inside it (what the operator acts on)."""
    head = lead(" ".join(str(why).split()))
    return len(fit_cell(f"{head}…", width).plain.split("\n"))


def wrapped_rows(rows, left: int) -> tuple[int, int, list[tuple[Text, Text]], list[int]]:
    """(why width, fix width, each row's why and fix wrapped, each row's lines) for the
    device table's last two columns within ``left``: the fix whole first (it says what to
    do), a longer text wrapped inside its cell."""
    fix_w = min(need("fix", [s.fix for s in rows]), max(left // 2, NOTE_MIN))
    why_w = max(NOTE_MIN, left - fix_w - 2)
    cells = [(fit_cell(s.why, why_w), fit_cell(s.fix, fix_w)) for s in rows]
    heights = [max(len(w.plain.split("\n")), len(f.plain.split("\n"))) for w, f in cells]
    return why_w, fix_w, cells, heights


def note_width(table: Any, rows: list[list], table_width: int, heads: Sequence = ()) -> int:
    """What the note column can show, cut with … (``note_room``, at least ``NOTE_MIN``)."""
    return max(NOTE_MIN, note_room(table, rows, table_width, heads))


def note_room(table: Any, rows: list[list], table_width: int, heads: Sequence = ()) -> int:
    """``table_width`` less the other columns (each as wide as its widest cell or header
    ``heads``, default the table's, plus its padding) and the note's own padding: below
    ``NOTE_MIN`` when the other columns take too much."""
    heads = heads or [str(c.label) for c in table.columns.values()][: len(rows[0]) if rows else 0]
    used = sum(w + 2 for w in widths(heads, rows))
    return table_width - used - 2
