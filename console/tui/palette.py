"""The command palette (ctrl+p) with the safety bar in view, where the main one is.

Textual's palette is a modal screen over the whole terminal: without its own bar it hid
whether the outputs were live or e-stopped while it was open.
"""

from __future__ import annotations

from textual.app import ComposeResult
from textual.command import CommandPalette

from console.tui.safety_bar import SafetyBar


class SafetyPalette(CommandPalette):
    """``CommandPalette`` keeping the output state visible (the app keeps it current)."""

    DEFAULT_CSS = """
    SafetyPalette > SafetyBar { dock: bottom; margin-bottom: 1; }  /* where the main one is */
    SafetyPalette > Vertical { margin-bottom: 2; }
    SafetyPalette #--results { max-height: 1fr; }
    """

    def compose(self) -> ComposeResult:
        yield from super().compose()
        yield SafetyBar()
