"""The command palette (ctrl+p) with the safety bar and a footer of its own keys in view,
where the main ones are.

Textual's palette is a modal screen over the whole terminal: without its own bar it hid
whether the outputs were live or e-stopped while it was open, and the row under it kept
the screen below's footer (``⏎ toggle 1-8 toggle`` on Relays: keys the palette does not
take). Its "Keys" opens the console's help; Textual's "Maximize" (a widget over the
whole terminal, the safety bar hidden) is left out (``console_system_commands``).
"""

from __future__ import annotations

from collections.abc import Callable, Iterable
from typing import Any

from textual.app import ComposeResult, SystemCommand
from textual.command import CommandPalette

from console.tui.narrow import ConsoleFooter
from console.tui.safety_bar import SafetyBar

#: Textual's commands that do not serve the operator: a widget maximized over the whole
#: terminal hides the safety bar and the footer (E-STOP)
LEFT_OUT = ("Maximize", "Minimize")


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
        yield PaletteFooter()  # the palette's keys and E-STOP, not the screen's below


class PaletteFooter(ConsoleFooter):
    """The palette's footer: Esc and E-STOP, the keys it takes (its search field types
    ``?``, and an F-key would switch the screen under it, the palette still open)."""

    ALWAYS = ("ctrl+e",)

    def _always(self) -> tuple[str, ...]:
        return self.ALWAYS


def console_system_commands(commands: Iterable[SystemCommand], show_help: Callable[[], Any]):
    """The palette's system commands with Textual's "Keys" (a panel docked at the right:
    it squeezed the screen, its tab bar down to ``Sc…``, and Esc left it open) opening
    the console's help instead: ``?``'s, the screen's keys and the console's, over the
    whole terminal, closed by Esc, ``?`` or ``q``; those in ``LEFT_OUT`` left out."""
    for cmd in commands:
        if cmd.title in LEFT_OUT:
            continue
        if cmd.title == "Keys":
            yield SystemCommand("Keys", "this screen's keys and the console's (?)", show_help)
        else:
            yield cmd
