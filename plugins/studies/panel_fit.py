"""The Studies screen's protocol dropdown sized to the protocols' names: closed, as wide
as the longest within what the form's first row leaves; open, its list as wide as the
longest name within the screen (a name never wraps)."""

from __future__ import annotations

from typing import Any

from textual.widgets import Select

from . import protocol as protocols

#: a compact Select's own columns beside the name: its padding and the "▼"
SELECT_EXTRA = 4
#: the open list's own columns: its border and each option's padding
LIST_EXTRA = 6
#: the rest of the form's first row at its widest: labels, participant, checkboxes, gaps
ROW_REST = 64
#: never narrower than this (the old fixed width)
MIN_W = 14


def protocol_width(names: list[str], screen_w: int) -> int:
    """Columns for the closed dropdown: the longest name and the Select's own, capped at
    what the row leaves on a ``screen_w``-column screen."""
    want = max([len(n) for n in names] or [0]) + SELECT_EXTRA
    return max(MIN_W, min(want, screen_w - ROW_REST))


def list_width(names: list[str], screen_w: int) -> int:
    """Columns for the open list: every name whole, within the screen."""
    want = max([len(n) for n in names] or [0]) + LIST_EXTRA
    return max(MIN_W, min(want, screen_w - 2))


def fit_protocols(pane: Any) -> None:
    """The dropdown and its list sized to the names at the screen's width now."""
    names, screen_w = protocols.available(), pane.app.size.width
    select = pane.query_one("#protocol", Select)
    select.styles.width = protocol_width(names, screen_w)
    select.query_one("SelectOverlay").styles.width = list_width(names, screen_w)


def mounted(pane: Any) -> None:
    """The pane is up: its dropdown sized to the names, then its idle status."""
    fit_protocols(pane)
    pane._idle()


def protocol_changed(pane: Any, name: str) -> None:
    """Another protocol chosen: the status says it (the last key's outcome, about the
    protocol before, is replaced) with what it needs, unless a run is going on."""
    if pane.running is not None:
        return
    pid = pane.query_one("#participant").value.strip() or "a participant"
    pane.said = (f"protocol {name} chosen: s starts it with {pid}", "information")
    pane._idle()
