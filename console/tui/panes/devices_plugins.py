"""The Devices screen's plugins table: every registration that is no screen of the
console (kind, name, plugin, description), its description within what the other
columns and the table's own scrollbar leave of the table's width."""

from __future__ import annotations

from typing import Any

from rich.text import Text
from textual.widgets import DataTable

from console.tui.device_cells import cell
from console.tui.table_fit import NOTE_MIN, widths

#: the plugins table's column heads
PLUGIN_HEADS = ("kind", "name", "plugin", "description")


def fill_plugins(plug: DataTable, pm: Any, table_width: int) -> dict[str, str]:
    """``plug`` filled with ``pm``'s registrations within ``table_width``; each row's key
    -> its plugin's line, whole (Enter on the row says it)."""
    regs = [
        (kind, name, reg)
        for kind, by_name in sorted(pm.registrations.items())
        for name, reg in sorted(by_name.items())
        if reg.tab is None  # a screen of the console: its tab shows it
    ]
    firsts = [[kind, name, reg.plugin] for kind, name, reg in regs]
    first_w = widths(PLUGIN_HEADS[:3], firsts)
    # the description takes what the other columns leave (each column has a cell of
    # padding either side) less the table's own scrollbar: its rows are more than a
    # screen holds, so it scrolls within the screen, and the bar covers its last columns
    # (``sound card through Port`` with its "…" under the bar at 80 columns)
    bar = plug.styles.scrollbar_size_vertical
    desc_w = max(NOTE_MIN, table_width - sum(w + 2 for w in first_w) - 2 - bar)
    plug.clear(columns=True)
    for head, width in zip(PLUGIN_HEADS, [*first_w, desc_w], strict=True):
        plug.add_column(head, width=width)
    rows: dict[str, str] = {}
    for kind, name, reg in regs:
        key = f"{kind}\x00{name}"
        rows[key] = f"{kind} {name} ({reg.plugin}): {reg.description}"
        about = cell(reg.description, f"{kind} {name}", desc_w)
        plug.add_row(Text(kind), Text(name), Text(reg.plugin), about, key=key)
    return rows
