"""A screen's ``:`` command line, the same on every screen that has one.

Enter hands the line's text to the screen (``on_command(text, line)``); what became of it
decides what the line holds: a command that failed keeps its text, the cursor at its end,
so the operator fixes it instead of typing it again; one that succeeded is cleared. A
command whose work runs on (an import, a load) keeps its text until that work says how it
ended (``succeeded``/``failed`` with the text it was given: a line typed over meanwhile
is left alone); when it failed the line takes the keys back. The line never selects its text on focus: a key typed after ``:`` adds
to what is there, it never replaces it. ``ctrl+u`` clears the whole line (wherever the
cursor is); ``escape`` leaves it (``CommandLine.Left``: the screen gives its keys back),
a failed command left unedited cleared with it.
An empty line shows its hint as a hint (dim, italic), after a ``:`` prompt that stays
whatever the line holds (``prompted``): never mistaken for a typed command. The line
takes paths (Vibration's ``load F.npz``, ``import PA=F.uff``): it is a ``PathField``,
typing every key, ``?`` too (``?`` opened the help from ``load /tmp/a?b``); Esc, then
``?``, shows the help.
"""

from __future__ import annotations

from textual.binding import Binding
from textual.containers import Horizontal
from textual.message import Message
from textual.widgets import Input, Label

from console.tui.focus_keys import name_field
from console.tui.path_field import PathField

__all__ = ["CommandLine", "prompted"]


class CommandPrompt(Horizontal):
    """A ``:`` prompt and its command line on one row."""

    DEFAULT_CSS = """
    CommandPrompt { height: 1; }
    CommandPrompt > Label { width: 2; color: $accent; text-style: bold; }
    CommandPrompt > CommandLine { width: 1fr; }
    """


def prompted(line: CommandLine) -> CommandPrompt:
    """``line`` after its ``:`` prompt (yield it where the line goes)."""
    return CommandPrompt(Label(": ", classes="command-prompt", markup=False), line)


class CommandLine(PathField):
    """The ``:`` line. The screen handles ``CommandLine.Submitted`` (an ``Input``
    message) and calls ``succeeded(text)`` or ``failed(text)``; it keeps the focus on
    the line after a failure and handles ``CommandLine.Left`` (escape)."""

    DEFAULT_CSS = """
    CommandLine > .input--placeholder { color: $text-muted; text-style: italic dim; }
    """
    BINDINGS = [
        Binding("ctrl+u", "clear_line", "clear the line", show=False),
        Binding("escape", "leave", "leave the line", show=False),
    ]

    class Left(Message):
        """Escape on the line: the screen's keys are wanted back (what was typed stays)."""

        def __init__(self, line: CommandLine) -> None:
            super().__init__()
            self.line = line

        @property
        def control(self) -> CommandLine:
            return self.line

    #: a failed command's text as kept (``failed``), until the operator edits it
    _kept: str | None = None

    def __init__(self, **kw) -> None:
        kw.setdefault("select_on_focus", False)
        kw.setdefault("compact", True)
        super().__init__(**kw)
        name_field(self, "command", enter="run", escape="leave")  # first in the footer

    def open(self) -> None:
        """``:``: the line takes the focus at once, the cursor after what it holds. At
        once, not after the keys queued behind ``:`` (``focus()`` waits for them): a
        command typed in one write with its ``:`` (tmux send-keys, a fast typist)
        reaches the line, not the screen's keys."""
        self.cursor_position = len(self.value)
        self.screen.set_focus(self)

    def succeeded(self, text: str) -> None:
        """The command ``text`` did what it was asked: the line is cleared (unless the
        operator has typed something else there since)."""
        if self.value.strip() == text.strip():
            self.value = ""

    def failed(self, text: str) -> None:
        """The command ``text`` failed: its text stays to be fixed, the cursor at the
        end (the screen's status line says why), and the line takes the keys back while
        its screen shows: a command whose work failed after the keys went back to the
        screen (a load, an import) is fixed there too, the letters typed next never act
        as the screen's keys."""
        if not self.value.strip():  # cleared meanwhile: bring the command back
            self.value = text
        if self.value.strip() == text.strip():
            self.cursor_position = len(self.value)
            self._kept = self.value
            if self.region.area and self.screen.focused is not self:
                self.screen.set_focus(self)

    def on_input_changed(self, event: Input.Changed) -> None:
        """``:`` typed at the end of a failed command, as it was kept, starts a new
        command (the operator typed ``:`` to give another one, not to glue it on); any
        other key edits the kept one."""
        kept = self._kept
        if event.input is not self or kept is None or event.value == kept:
            return
        self._kept = None
        if event.value == kept + ":":
            self.value = ""

    def action_clear_line(self) -> None:
        """``ctrl+u``: the whole line cleared (ctrl+z brings it back)."""
        self.delete(0, len(self.value))

    def action_leave(self) -> None:
        """``escape``: the screen takes its keys back; a failed command left as it was
        kept goes with it (given up: it stayed for the rest of the session)."""
        if self._kept is not None and self.value == self._kept:
            self._kept = None
            self.value = ""
        self.post_message(self.Left(self))
