"""The Studies screen's trials table: every column whole at any width (the trial's
description gives what the others leave, ending in ``…``), and the newest trial followed
(the cursor on it, its row in view, also when the status above grows and the table
shrinks) unless the operator moved the cursor off the newest row."""

from __future__ import annotations

from typing import Any

from textual import events
from textual.widgets.data_table import ColumnKey

from console.plugin_api.tui import LiteralTable

from .panel_text import clip


class TrialsTable(LiteralTable):
    """A done trial a row: trial, what, response, correct, replays, time."""

    def __init__(self, **kw: Any) -> None:
        super().__init__(**kw)
        self.whats: dict[Any, str] = {}  # row -> its whole description
        self.what_room = 40  # the columns the description gets (``fit``)

    def clear_trials(self) -> None:
        """No rows (a new run)."""
        self.clear()
        self.whats.clear()

    def add_trial(self, trial: str, what: str, *rest: str) -> Any:
        """Add a done trial's row; the cursor follows it when it was on the newest row."""
        follow = self.row_count == 0 or self.cursor_row >= self.row_count - 1
        key = self.add_row(trial, clip(what, self.what_room), *rest)
        self.whats[key] = what
        self.fit()
        self.call_after_refresh(self.fit)  # once the table measured the new row
        if follow:
            self.move_cursor(row=self.row_count - 1)
        return key

    def fit(self) -> None:
        """Every column whole at this width (80 columns: the time too)."""
        width = self.size.width or self.app.size.width
        others = sum(c.get_render_width(self) for k, c in self.columns.items() if k.value != "what")
        # its padding, and room for the scrollbar that more rows bring
        room = max(12, width - others - 2 * self.cell_padding - 2)
        if room == self.what_room:
            return
        self.what_room = room
        column = self.columns.get(ColumnKey("what"))
        if column is not None:  # a set width: a column's widest cell never shrinks it
            column.auto_width, column.width = False, room
        for key, what in self.whats.items():
            if key in self.rows:
                self.update_cell(key, "what", clip(what, room))
        self.refresh(layout=True)

    def on_resize(self, event: events.Resize) -> None:
        """Another size: the columns fitted again, the cursor's row back in view (the
        status above took a line)."""
        self.call_after_refresh(self.fit)
        if self.row_count:
            self.call_after_refresh(lambda: self.move_cursor(row=self.cursor_row))
