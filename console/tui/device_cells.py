"""The Devices screen's table cells: within their column, a cut text logged whole once
(the log, ctrl+l, has what a cell could not show; Enter on the row says it)."""

from __future__ import annotations

import logging

from rich.text import Text

from console.tui.table_fit import clip, fit_lines

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
