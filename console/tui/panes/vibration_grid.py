"""The Vibration screen's grid: enter auditions the point under the cursor, and the
footer says so first (the focused widget's keys come first there; ``DataTable``'s own
enter is left out of the footer)."""

from __future__ import annotations

from textual.binding import Binding

from console.tui.text import LiteralTable


class PointGrid(LiteralTable):
    """The map's points laid out as a grid; enter selects the cell (the pane auditions
    it: ``VibrationPane.on_data_table_cell_selected``)."""

    BINDINGS = [Binding("enter", "select_cursor", "audition")]
