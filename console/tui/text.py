"""Dynamic text shown as written.

Textual reads square brackets in a string as markup wherever a string becomes text on
the screen: ``Static``/``Label`` content, notifications and ``DataTable`` cells. A
profile key in a message (``[audio] device``), a plugin's description (``[tuio]
enabled``) or a file name would lose its brackets, or break the line's style. The
console keeps markup for its own templates and shows every value literally:

- notifications are literal (``HapTableApp.notify``: ``markup=False`` unless asked);
- tables are ``LiteralTable``: a ``str`` cell or column label is plain text; a styled
  cell is given as ``styled(text, style)``;
- a template with markup escapes what it interpolates (``escape``, or a number with a
  format spec): ``tests/tui/test_literal_text.py`` checks every f-string with markup;
- a widget showing only dynamic text is built with ``markup=False``.
"""

from __future__ import annotations

from typing import Any

from rich.text import Text
from textual.markup import escape as _escape
from textual.widgets import DataTable

__all__ = ["LiteralTable", "escape", "literal", "styled"]


def escape(value: Any) -> str:
    """``value`` as text for a markup template: its square brackets stay as written."""
    return _escape(str(value))


def literal(value: Any) -> Any:
    """``value`` as a table cell shown as written (a ``str`` becomes plain ``Text``;
    numbers and renderables pass unchanged)."""
    return Text(value) if isinstance(value, str) else value


def one_line(value: Any) -> Any:
    """``literal`` for a row one line high: a cell its column cuts ends in ``…``."""
    return Text(value, no_wrap=True, overflow="ellipsis") if isinstance(value, str) else value


def styled(text: str, style: str) -> Text:
    """``text`` shown as written, in ``style`` (e.g. ``"green"``, ``"bold reverse"``)."""
    return Text(text, style=style)


class LiteralTable(DataTable):
    """A ``DataTable`` whose ``str`` cells and column labels are shown as written, and
    whose highlighted row stays in view when the table gets shorter (a line above it
    grew, a notification took rows, the terminal was made smaller)."""

    def on_resize(self, _event: Any) -> None:
        if self.show_cursor and self.cursor_type != "none" and self.row_count:
            self.call_after_refresh(self.move_cursor, animate=False)  # scrolls to it

    def add_column(self, label: Any, *args: Any, **kw: Any) -> Any:
        return super().add_column(literal(label), *args, **kw)

    def add_row(self, *cells: Any, **kw: Any) -> Any:
        label = kw.get("label")
        if label is not None:
            kw["label"] = literal(label)
        cell = one_line if kw.get("height", 1) == 1 else literal  # a cut cell says so
        return super().add_row(*(cell(c) for c in cells), **kw)

    def _cell(self, row_key: Any) -> Any:
        row = self.rows.get(row_key)
        return one_line if row is not None and row.height == 1 else literal

    def update_cell(self, row_key: Any, column_key: Any, value: Any, **kw: Any) -> None:
        super().update_cell(row_key, column_key, self._cell(row_key)(value), **kw)

    def update_cell_at(self, coordinate: Any, value: Any, **kw: Any) -> None:
        key = self.coordinate_to_cell_key(coordinate).row_key
        super().update_cell_at(coordinate, self._cell(key)(value), **kw)
