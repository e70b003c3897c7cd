"""The help (``?``) over the whole terminal, with the safety bar and a footer of its own
keys where the main ones are: Esc closes it, the arrows and PageUp/PageDown scroll it,
E-STOP and the screens' F-keys (one closes the help and shows its screen). Without its
own footer the row under it kept the screen's below (Camera: ``v view k calibrate``,
keys the help does not take, and no Esc)."""

from __future__ import annotations

from textual.app import ComposeResult
from textual.binding import Binding
from textual.containers import VerticalScroll
from textual.screen import ModalScreen

from console.tui.help import HelpText
from console.tui.narrow import ConsoleFooter
from console.tui.safety_bar import SafetyBar

__all__ = ["HelpFooter", "HelpScreen"]


class HelpFooter(ConsoleFooter):
    """The help's footer: its own keys, E-STOP and the screens' F-keys (``?`` closes it
    as Esc does: said once, as ``esc close``)."""

    ALWAYS = ("ctrl+e",)


class HelpScreen(ModalScreen):
    """The console's keys and the screen's own help, as written and wrapped to the
    terminal (``console.tui.help``). ``?`` (the app's, from any field) closes it too."""

    BINDINGS = [
        Binding("escape,q,question_mark", "dismiss", "close", key_display="esc"),
        Binding("pagedown", "scroll_help('page_down')", "scroll", key_display="↑↓ PgUp PgDn"),
        Binding("pageup", "scroll_help('page_up')", "scroll up", show=False),
        Binding("down", "scroll_help('down')", "scroll down", show=False),
        Binding("up", "scroll_help('up')", "scroll up", show=False),
        Binding("home", "scroll_help('home')", "top", show=False),
        Binding("end", "scroll_help('end')", "end", show=False),
    ]
    DEFAULT_CSS = """
    HelpScreen { align: center middle; }
    HelpScreen > SafetyBar { dock: bottom; margin-bottom: 1; }  /* where the main one is */
    HelpScreen > HelpFooter { dock: bottom; }
    HelpScreen > VerticalScroll { width: 90; max-width: 100%; height: auto; max-height: 90%;
        border: thick $accent; background: $panel; padding: 0 1; }
    """

    def __init__(self, sections: list[tuple[str, str]]) -> None:
        super().__init__()
        self.sections = sections  # (title, text as written)

    def compose(self) -> ComposeResult:
        with VerticalScroll(id="help-scroll", can_focus=False):  # its keys: the screen's
            yield HelpText(self.sections, id="help-text")
        yield SafetyBar()  # the output state stays in view (the app keeps it current)
        yield HelpFooter()  # the help's keys, not the screen's below

    def on_mount(self) -> None:
        self.call_after_refresh(self.refresh_bindings)  # laid out: whether it scrolls

    def on_resize(self) -> None:
        self.call_after_refresh(self.refresh_bindings)

    def check_action(self, action: str, parameters: tuple) -> bool | None:
        """The scrolling keys only where the help is longer than its box (a key shown
        that does nothing is what this footer is for not doing)."""
        if action == "scroll_help":
            found = self.query("#help-scroll")
            return bool(found) and found.first().max_scroll_y > 0
        return True

    def action_scroll_help(self, how: str) -> None:
        """The help scrolled (``page_down``, ``up`` ...), wherever the focus is."""
        box = self.query_one("#help-scroll", VerticalScroll)
        steps = {
            "page_down": box.scroll_page_down,
            "page_up": box.scroll_page_up,
            "down": box.scroll_down,
            "up": box.scroll_up,
            "home": box.scroll_home,
            "end": box.scroll_end,
        }
        steps[how](animate=False)

    def leave_for_screen(self) -> bool:
        """An F-key closes the help to show its screen (``LeavesForScreen``)."""
        self.dismiss()
        return True
