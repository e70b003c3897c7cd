"""The Vibration screen's grid: enter auditions the point under the cursor, and the
footer says so first (the focused widget's keys come first there; ``DataTable``'s own
enter is left out of the footer); page up / page down scroll the screen (the FRF plot's
axes and legend below the grid at 80 x 24) while the grid keeps the focus and its
cursor."""

from __future__ import annotations

from textual.binding import Binding
from textual.containers import ScrollableContainer

from console.tui.text import LiteralTable


class PointGrid(LiteralTable):
    """The map's points laid out as a grid; enter selects the cell (the pane auditions
    it: ``VibrationPane.on_data_table_cell_selected``)."""

    BINDINGS = [
        Binding("enter", "select_cursor", "audition"),
        Binding("pageup", "scroll_screen(-1)", "scroll up", show=False),
        Binding("pagedown", "scroll_screen(1)", "scroll down", show=False),
    ]

    def action_scroll_screen(self, step: int) -> None:
        """A page of the screen around the grid (the grid shows whole: its own pages
        would only move the cursor)."""
        pane = next((a for a in self.ancestors if isinstance(a, ScrollableContainer)), None)
        if pane is not None:
            (pane.scroll_page_down if step > 0 else pane.scroll_page_up)(animate=False)
