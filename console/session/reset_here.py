"""Why ctrl+r resets nothing in a console that holds no outputs, and where it resets.

A second console of a profile (another one holds its lock and outputs), or one whose
outputs are not open, has no kernel to ask: its ctrl+r says so in one line, with the
fix (ctrl+r in the console that holds the outputs, or the reset command at a terminal).
"""

from __future__ import annotations

from typing import Any

from console.kernel.shell import reset_command
from console.kernel.tables import read_latch, table_for
from console.runtime.control import holder_of


def no_reset_here(profile: Any, outputs_error: str, console_elsewhere: bool) -> str:
    """The one line ctrl+r gives without outputs: ``profile``'s table not e-stopped,
    held by another console (``console_elsewhere``), still opening, or not open
    (``outputs_error``: why)."""
    table = table_for(profile.path)
    command = reset_command(table, None)
    if read_latch(table) is None:
        return f"no e-stop to reset: table {table.name} is not e-stopped"
    if console_elsewhere:
        return (
            f"not reset here: ctrl+r in the console holding the outputs{holder_of(profile)}, "
            f"or `{command}` at a terminal"
        )
    if not outputs_error:
        return "ctrl+r: the outputs are still opening; press it again once the bar shows them"
    return (
        f"ctrl+r resets nothing here: the outputs are not open ({outputs_error}); "
        f"`{command}` at a terminal"
    )
