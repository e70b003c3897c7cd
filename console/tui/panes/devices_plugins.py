"""The Devices screen's plugins table: every registration that is no screen of the
console (kind, name, plugin, description), its description within what the other
columns leave of the table's width."""

from __future__ import annotations

from typing import Any

from rich.text import Text
from textual.widgets import DataTable

from console.tui.device_cells import cell

#: the plugins table's description column at least (at 80 columns: the table fits)
PLUGIN_DESC_MAX = 24


def fill_plugins(plug: DataTable, pm: Any, table_width: int) -> dict[str, str]:
    """``plug`` filled with ``pm``'s registrations within ``table_width``; each row's key
    -> its plugin's line, whole (Enter on the row says it)."""
    plug.clear(columns=True)
    plug.add_columns("kind", "name", "plugin", "description")
    regs = [
        (kind, name, reg)
        for kind, by_name in sorted(pm.registrations.items())
        for name, reg in sorted(by_name.items())
        if reg.tab is None  # a screen of the console: its tab shows it
    ]
    # the description takes what the other columns leave of the screen (each column
    # has a cell of padding either side), at least PLUGIN_DESC_MAX
    cells = [(kind, name, reg.plugin) for kind, name, reg in regs]
    others = sum(max(map(len, col), default=0) + 2 for col in zip(*cells, strict=True))
    width = max(PLUGIN_DESC_MAX, table_width - others - 4)
    rows: dict[str, str] = {}
    for kind, name, reg in regs:
        key = f"{kind}\x00{name}"
        rows[key] = f"{kind} {name} ({reg.plugin}): {reg.description}"
        about = cell(reg.description, f"{kind} {name}", width)
        plug.add_row(Text(kind), Text(name), Text(reg.plugin), about, key=key)
    return rows
