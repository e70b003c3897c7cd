"""The command palette (ctrl+p) with the safety bar in view, where the main one is.

Textual's palette is a modal screen over the whole terminal: without its own bar it hid
whether the outputs were live or e-stopped while it was open. Its "Keys" opens the
console's help (``keys_as_console_help``).
"""

from __future__ import annotations

from collections.abc import Callable, Iterable
from typing import Any

from textual.app import ComposeResult, SystemCommand
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


def keys_as_console_help(commands: Iterable[SystemCommand], show_help: Callable[[], Any]):
    """The palette's system commands with Textual's "Keys" (a panel docked at the right:
    it squeezed the screen, its tab bar down to ``Sc…``, and Esc left it open) opening
    the console's help instead: ``?``'s, the screen's keys and the console's, over the
    whole terminal, closed by Esc, ``?`` or ``q``."""
    for cmd in commands:
        if cmd.title == "Keys":
            yield SystemCommand("Keys", "this screen's keys and the console's (?)", show_help)
        else:
            yield cmd
